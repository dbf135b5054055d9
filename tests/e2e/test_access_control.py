"""The secure split: TLS + user/password + access control on the robot's router (router, emulator
and driver processes)."""

from __future__ import annotations

import json
import shutil
import sys
import time

import pytest
import zenoh

from common import runauth
from common.ros_link import BridgeTopics
from common.transport import wait_alive, zenoh_config
from nodes.base_driver.rosbot import cdr_to_robot_odom, twist_to_cdr
from papf.launch.supervisor import free_port, wait_port
from papf.robot.certs import Bundle, write_bundle
from schemas import Keys, Twist
from tests.support.cli import papf

NS, BRIDGE = "t5sec", "bot"


@pytest.fixture(scope="module")
def secure_robot(tmp_path_factory):
    """Router (TLS + auth + ACL), emulator and rosbot driver; yields (bundle, endpoints, trace)."""
    if shutil.which("openssl") is None:
        pytest.skip("the openssl command is needed to make test certificates")
    from papf.launch.supervisor import Supervisor

    tcp_port, tls_port = free_port(), free_port()
    made = tmp_path_factory.mktemp("made") / "bundle"
    write_bundle(made, ["127.0.0.1"], NS, BridgeTopics(BRIDGE), tcp_port, tls_port)
    out = tmp_path_factory.mktemp("certs") / "copied"      # the bundle works where it is copied
    shutil.copytree(made, out)
    shutil.rmtree(made)
    bundle = Bundle(out)
    tcp, tls = f"tcp/127.0.0.1:{tcp_port}", f"tls/127.0.0.1:{tls_port}"
    trace = out / "trace.jsonl"
    py, robot = sys.executable, ["--zenoh-config", str(bundle.robot), "--namespace", NS]
    with Supervisor(show=lambda n, line: "WARN" in line or "rror" in line) as sup:
        sup.start("router", [py, "-m", "papf.launch.router", "--listen", tcp, "--listen", tls,
                             "--zenoh-config", str(bundle.router)])
        assert wait_port(tcp_port, 15.0), " | ".join(sup.children[0].tail)
        sup.start("emulator", [py, "-m", "papf", "rosbot-emulator", *robot, "--bridge-namespace", BRIDGE,
                               "--cmd-timeout", "0", "--trace", str(trace)])
        sup.start("base_driver", [py, "-m", "nodes.base_driver", "--driver", "rosbot", *robot,
                                  "--bridge-namespace", BRIDGE],
                  env={runauth.ENV: _pair_key().hex()})   # as papf launch hil-robot would
        with zenoh.open(zenoh_config("client", [tcp], config_file=str(bundle.robot))) as s:
            missing = wait_alive(s, Keys(NS), ["base_driver", "rosbot_emulator"], 30.0)
        assert not missing, [list(c.tail) for c in sup.children]
        yield bundle, tcp, tls, trace


def _pair_key() -> bytes:
    """This host's pairing key of NS (the laptop launch below takes it without --key)."""
    path = runauth.pair_file(NS)
    path.parent.mkdir(mode=0o700, exist_ok=True)
    return runauth.load_pair_key(path, create=True)[0]


def _commands(trace) -> list[dict]:
    """The emulator's trace so far: its complete lines (it may be writing the last one)."""
    text = trace.read_text() if trace.exists() else ""
    return [json.loads(line) for line in text.split("\n")[:-1] if line]


def test_peer_without_credentials_cannot_connect(secure_robot):
    _, tcp, tls, _ = secure_robot
    for endpoint in (tcp, tls):                   # no password; no client certificate either
        with pytest.raises(zenoh.ZError, match="Unable to connect"):
            zenoh.open(zenoh_config("client", [endpoint]))


def test_wrong_password_cannot_connect(secure_robot, tmp_path):
    bundle, _, tls, _ = secure_robot
    conf = json.loads(bundle.observer.read_text())
    conf["transport"]["auth"]["usrpwd"]["password"] = "guessed"
    path = tmp_path / "wrong.json5"
    path.write_text(json.dumps(conf))
    with pytest.raises(zenoh.ZError, match="Unable to connect"):
        zenoh.open(zenoh_config("client", [tls], config_file=str(path)))


def test_valid_credentials_but_not_the_planner_cannot_move_the_robot(secure_robot):
    bundle, _, tls, trace = secure_robot
    keys = Keys(NS)
    seen = []
    with zenoh.open(zenoh_config("client", [tls], config_file=str(bundle.observer))) as s:
        sub = s.declare_subscriber(f"{BRIDGE}/odometry/filtered",
                                   lambda smp: seen.append(cdr_to_robot_odom(smp.payload.to_bytes())))
        for i in range(15):     # 1.5 s of turning right (w < 0) on both cmd_vel keys
            s.put(keys.cmd_vel, Twist(stamp_ns=i, v=0.5, w=-1.0).to_bytes())
            s.put(f"{BRIDGE}/cmd_vel", twist_to_cdr(0.5, -1.0))
            time.sleep(0.1)
        time.sleep(0.5)
        deadline = time.monotonic() + 30      # the odometry may come late on a busy machine
        while not seen and time.monotonic() < deadline:
            time.sleep(0.05)
        sub.undeclare()
    assert seen, "the observer may read the robot's odometry"
    assert not [c for c in _commands(trace) if c["w"] < 0], "an observer's command got through"
    assert seen[-1].pose.yaw >= 0.0


def test_robot_password_with_the_laptop_certificate_cannot_move_the_robot(secure_robot,
                                                                          tmp_path):
    """The ACL binds identities to how they connect: the robot's password over the external
    TLS listener (with the laptop's certificate) matches no subject, so its cmd_vel on the
    bridge key never reaches the robot past the driver's limits and watchdog."""
    bundle, _, tls, trace = secure_robot
    conf = json.loads(bundle.laptop.read_text())
    robot_pwd = json.loads(bundle.robot.read_text())["transport"]["auth"]["usrpwd"]
    conf["transport"]["auth"]["usrpwd"] = robot_pwd
    path = bundle.dir / "stolen.json5"          # beside the certificates it names
    path.write_text(json.dumps(conf))
    try:
        with zenoh.open(zenoh_config("client", [tls], config_file=str(path))) as s:
            for _ in range(15):
                s.put(f"{BRIDGE}/cmd_vel", twist_to_cdr(0.4, -2.0))
                time.sleep(0.1)
            time.sleep(0.5)
    except zenoh.ZError:
        pass                                     # refused outright is fine too
    finally:
        path.unlink()
    assert not [c for c in _commands(trace) if c["w"] < -1.5], "the robot's password over TLS moved it"


def test_the_planner_identity_moves_the_robot(secure_robot):
    bundle, _, tls, trace = secure_robot
    keys = Keys(NS)
    with zenoh.open(zenoh_config("client", [tls], config_file=str(bundle.laptop))) as s:
        deadline = time.monotonic() + 30.0
        while time.monotonic() < deadline and not any(c["v"] > 0 for c in _commands(trace)):
            runauth.sealed_put(s, keys.cmd_vel, Twist(stamp_ns=0, v=0.3, w=0.0).to_bytes(),
                               _pair_key())   # the driver obeys the pairing key only
            time.sleep(0.1)
    assert any(c["v"] > 0 for c in _commands(trace))


def test_the_planner_lists_the_nodes_behind_the_bridge(secure_robot):
    """The bridge's admin space (answered here by the emulator) passes the ACL, whose "**"
    matches no "@" chunk (the observer queries nothing: its node list has no ROS nodes)."""

    bundle, _, tls, _ = secure_robot
    r = papf("node", "list", "--namespace", NS, "--connect", tls, "--zenoh-config",
             str(bundle.laptop), timeout=60)
    assert r.returncode == 0, r.stderr
    assert any(line.startswith("/rosbot_emulator  (ROS 2, zenoh-bridge-ros2dds ")
               for line in r.stdout.splitlines()), r.stdout


def test_secure_hil_run_reaches_the_goal(secure_robot, tmp_path):
    """The rules let a whole run through: the laptop's LiDAR, planner and meter over mTLS."""

    bundle, _, tls, _ = secure_robot
    world = tmp_path / "short.toml"
    world.write_text('name = "short"\n[goal]\nposition = [1.0, 0.0]\ntolerance = 0.15\n'
                     '[[obstacles]]\nkind = "cylinder"\ncenter = [0.5, 0.6]\nradius = 0.15\n')
    out = papf("launch", "hil-laptop", "--zenoh-config", str(bundle.laptop), "--connect", tls,
               "--namespace", NS, "--world", str(world), "--json", "--timeout", "30", "--set",
               "v_max=0.5", timeout=120)
    assert out.stdout.strip(), out.stderr[-2000:]
    result = json.loads(out.stdout.strip().splitlines()[-1])
    assert result["outcome"] == "reached", (result, out.stderr[-2000:])
    assert result["charge_mAh"] > 0                 # the meter's battery got through too


def test_a_command_without_credentials_is_told_authentication_failed(secure_robot, tmp_path):
    """No certificate (or a wrong password): one line naming the authentication, not "is a
    stack running?" (the router is up)."""

    bundle, tcp, tls, _ = secure_robot
    conf = json.loads(bundle.observer.read_text())
    conf["transport"]["auth"]["usrpwd"]["password"] = "guessed"
    wrong = tmp_path / "wrong.json5"
    wrong.write_text(json.dumps(conf))
    for extra, said in ((["--connect", tls], "has none"), (["--connect", tcp], "asks for credentials"),
                        (["--zenoh-config", str(wrong)], "refused the credentials of")):
        r = papf("topic", "list", "--namespace", NS, *extra, timeout=60)
        assert r.returncode == 2 and "authentication failed" in r.stderr and said in r.stderr, \
            (extra, r.stderr)
        assert "stack running" not in r.stderr and "Traceback" not in r.stderr
