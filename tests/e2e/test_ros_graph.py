"""papf node list|info and papf topic info see the emulated ROSbot, a process that is not
the tool, on both middlewares: its rmw_zenoh tokens, or the bridge's admin space it answers."""

from __future__ import annotations

import sys

import pytest

from common.transport import wait_alive
from schemas import Keys
from tests.support import warm

DOMAIN = 13


def papf(*argv, router):
    return warm.run([sys.executable, "-m", "papf", *argv, "--connect", router], timeout=60)


@pytest.mark.e2e
@pytest.mark.parametrize("middleware", ["rmw_zenoh", "bridge"])
def test_the_emulated_rosbot_is_in_the_ros_graph(router, spawn, session, middleware):
    keys = Keys(f"graph{middleware.replace('_', '')}")
    ros = ["--ros", middleware, "--ros-domain", str(DOMAIN)]
    spawn("emulator", [sys.executable, "-m", "papf", "rosbot-emulator", "--connect", router,
                       "--namespace", keys.ns, *ros])
    assert not wait_alive(session, keys, ["rosbot_emulator"], 30.0)
    r = papf("node", "list", "--namespace", keys.ns, *ros, router=router)
    assert r.returncode == 0, r.stderr
    assert f"{keys.ns}/rosbot_emulator" in r.stdout.splitlines()
    assert any(line.startswith("/rosbot_emulator  (ROS 2, ") for line in r.stdout.splitlines())
    r = papf("node", "info", "/rosbot_emulator", *ros, router=router)
    assert r.returncode == 0, r.stderr
    assert "    /cmd_vel: geometry_msgs/msg/Twist" in r.stdout
    assert "    /odometry/filtered: nav_msgs/msg/Odometry" in r.stdout
    assert "    /battery: sensor_msgs/msg/BatteryState" in r.stdout
    r = papf("topic", "info", "/odometry/filtered", *ros, router=router)
    assert r.returncode == 0, r.stderr
    assert "Type: nav_msgs/msg/Odometry" in r.stdout
    assert "Publisher count: 1\n  /rosbot_emulator" in r.stdout
