"""The rosbot driver and the ROSbot emulator as processes over a router."""

from __future__ import annotations

import sys
import time

from common.transport import wait_alive
from nodes.base_driver.rosbot import (
    cdr_to_robot_odom,
)
from schemas import Event, Keys, Twist
from schemas.keys import TOPICS

MS = 1_000_000


# -- processes: driver + emulator through a router ----------------------------------------------
def _collect(session, keys, topics, out):
    def cb(topic):
        return lambda s: out.append((time.monotonic(), topic,
                                     TOPICS[topic].from_bytes(s.payload.to_bytes())))
    return [session.declare_subscriber(keys.key(t), cb(t)) for t in topics]


def test_driver_and_emulator_processes(router, spawn, session):
    keys, py = Keys("t5drv"), sys.executable
    z = ["--connect", router, "--namespace", keys.ns]
    spawn("emulator", [py, "-m", "papf", "rosbot-emulator", *z, "--bridge-namespace", "bot",
                       "--cmd-timeout", "0"])
    spawn("base_driver", [py, "-m", "nodes.base_driver", "--driver", "rosbot", *z,
                          "--bridge-namespace", "bot", "--world", "open"])
    assert not wait_alive(session, keys, ["base_driver", "rosbot_emulator"], 30.0)
    got, robot = [], []
    subs = _collect(session, keys, ("odom", "wheels", "clock", "events"), got)
    subs.append(session.declare_subscriber("bot/odometry/filtered", lambda s: robot.append(
        (time.monotonic(), cdr_to_robot_odom(s.payload.to_bytes())))))
    session.put("bot/odometry/filtered", b"not CDR")          # a bad robot message: dropped
    session.put(keys.events, Event(stamp_ns=0, kind="run_started", source="test").to_bytes())
    t0 = time.monotonic()
    while time.monotonic() - t0 < 1.5:                        # 10 Hz commands, stamped now
        stamp = int((time.monotonic() - t0) * 1e9)
        session.put(keys.cmd_vel, Twist(stamp_ns=stamp, v=0.4, w=0.2).to_bytes())
        time.sleep(0.1)
    t_last = time.monotonic()
    deadline = t_last + 30.0
    while time.monotonic() < deadline and not (
            any(k == "events" and m.kind == "watchdog_stop" for _, k, m in got)
            and robot and robot[-1][0] > t_last and robot[-1][1].v == 0.0):
        time.sleep(0.05)
    for s in subs:
        s.undeclare()
    odoms = [m for _, k, m in got if k == "odom"]
    wheels = {m.stamp_ns for _, k, m in got if k == "wheels"}
    assert odoms and odoms[-1].x > 0.2 and odoms[-1].yaw > 0.05
    assert {o.stamp_ns for o in odoms} <= wheels | {odoms[-1].stamp_ns}
    assert all(o.stamp_ns % (20 * MS) == 0 for o in odoms)
    assert any(k == "events" and m.kind == "watchdog_stop" for _, k, m in got)
    assert robot[-1][1].v == 0.0 and robot[-1][1].w == 0.0   # only our watchdog could stop it
