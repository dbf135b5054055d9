"""The secure split on rmw_zenoh: the bundle's rmw_zenohd config (TLS + passwords + access
control) on a router standing in for rmw_zenohd, the emulated ROSbot as a ROS 2 peer with
the bundle's session config, our router and rosbot driver joined to it as ``robot``; the
laptop over TLS. Only the planner's command on our key reaches the wheels, through the driver."""

from __future__ import annotations

import json
import shutil
import sys
import time

import pytest
import zenoh

from common.transport import wait_alive, zenoh_config
from nodes.base_driver.rosbot import twist_to_cdr
from papf.launch.supervisor import Supervisor, free_port, wait_port
from papf.robot.certs import write_bundle
from schemas import Keys, Twist

NS, DOMAIN = "rmwsec", 21
CMD_KEY = (f"{DOMAIN}/cmd_vel/geometry_msgs::msg::dds_::Twist_/"
           "RIHS01_9c45bf16fe0983d80e3cfe750d6835843d265a9a6c46bd2e609fcddde6fb8d2a")


def _commands(trace) -> list[dict]:
    text = trace.read_text() if trace.exists() else ""
    return [json.loads(line) for line in text.split("\n")[:-1] if line]


@pytest.mark.e2e
def test_only_the_planner_moves_the_robot_over_secure_rmw_zenoh(tmp_path):
    if shutil.which("openssl") is None:
        pytest.skip("the openssl command is needed to make test certificates")
    rmw_port, tls_port, papf_port = free_port(), free_port(), free_port()
    b = write_bundle(tmp_path / "bundle", ["127.0.0.1"], NS, None, rmw_port, tls_port,
                     ros="rmw_zenoh", ros_domain=DOMAIN, papf_port=papf_port)
    tls = f"tls/127.0.0.1:{tls_port}"
    trace = tmp_path / "trace.jsonl"
    py, ros = sys.executable, ["--ros", "rmw_zenoh", "--ros-domain", str(DOMAIN), "--namespace", NS]
    with Supervisor(show=lambda n, line: "WARN" in line or "rror" in line) as sup:
        sup.start("rmw_zenohd", [py, "-m", "papf.launch.router", "--zenoh-config", str(b.rmw_zenohd),
                                 "--listen", f"tcp/127.0.0.1:{rmw_port}", "--listen", tls])
        assert wait_port(rmw_port, 15.0), " | ".join(sup.children[0].tail)
        sup.start("emulator", [py, "-m", "papf", "rosbot-emulator", *ros, "--mode", "peer",
                               "--zenoh-config", str(b.ros_session), "--cmd-timeout", "0",
                               "--trace", str(trace)])
        sup.start("router", [py, "-m", "papf.launch.router", "--zenoh-config", str(b.router),
                             "--listen", f"tcp/127.0.0.1:{papf_port}"])
        assert wait_port(papf_port, 15.0), " | ".join(sup.children[-1].tail)
        sup.start("base_driver", [py, "-m", "nodes.base_driver", "--driver", "rosbot", *ros,
                                  "--zenoh-config", str(b.robot)])
        with zenoh.open(zenoh_config("client", config_file=str(b.laptop))) as planner, \
                zenoh.open(zenoh_config("client", config_file=str(b.observer))) as observer:
            missing = wait_alive(planner, Keys(NS), ["base_driver", "rosbot_emulator"], 60.0)
            assert not missing, [list(c.tail) for c in sup.children]
            odoms = []
            sub = planner.declare_subscriber(Keys(NS).odom, lambda s: odoms.append(1))
            for i in range(15):   # 1.5 s: the planner turns left; the others try right (w < 0)
                planner.put(Keys(NS).cmd_vel, Twist(stamp_ns=i, v=0.1, w=0.3).to_bytes())
                planner.put(CMD_KEY, twist_to_cdr(0.4, -2.0))       # past the driver: denied
                observer.put(Keys(NS).cmd_vel, Twist(stamp_ns=i, v=0.5, w=-1.0).to_bytes())
                observer.put(CMD_KEY, twist_to_cdr(0.4, -2.0))
                time.sleep(0.1)
            deadline = time.monotonic() + 30
            while time.monotonic() < deadline and not (odoms and any(
                    c["w"] > 0.2 for c in _commands(trace))):
                time.sleep(0.05)
            sub.undeclare()
    cmds = _commands(trace)
    assert any(c["w"] > 0.2 for c in cmds), "the planner's command did not reach the robot"
    assert not [c for c in cmds if c["w"] < 0], "a command that is not the planner's got through"
    assert odoms, "the laptop may read the robot's odometry"
