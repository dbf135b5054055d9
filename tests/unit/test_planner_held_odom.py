"""HeldOdometry: lockstep odometry kept off the planner's main thread, the same answers."""

from __future__ import annotations

import numpy as np

from nodes.planner.loop import HeldOdometry, PlannerLoop
from nodes.planner.registry import make_planner
from schemas.messages import Goal, Odometry, Scan

DT = 20_000_000   # [ns] odometry period (50 Hz)


def _odom(t):
    return Odometry(stamp_ns=t, x=0.01 * t / DT, y=0.0, yaw=0.0, v=0.2, w=0.0)


def _scan(t):
    ranges = np.full(60, np.inf, np.float32)
    ranges[10] = 1.5
    return Scan(stamp_ns=t, angle_min=0.0, angle_increment=0.1, range_min=0.1, range_max=10.0,
                ranges=ranges)


def _arrivals():
    """Five odometry messages per scan; every third scan arrives before its odometry."""
    out = []
    for k in range(12):
        t = 5 * k * DT
        odoms = [("odom", _odom(t + i * DT)) for i in range(-4, 1) if t + i * DT >= 0]
        out += [("scan", _scan(t)), *odoms] if k % 3 == 2 else [*odoms, ("scan", _scan(t))]
    return out


def test_held_odometry_gives_the_loop_the_same_answers_with_fewer_wakes():
    goal = Goal(stamp_ns=0, x=5.0, y=0.0)
    plain = PlannerLoop(make_planner("apf"), want_state=lambda: False)  # no timings
    expected = plain.on_message("goal", goal, 0.0)
    for topic, msg in _arrivals():
        expected += plain.on_message(topic, msg, 0.0)

    loop, wakes = PlannerLoop(make_planner("apf"), want_state=lambda: False), []
    held = HeldOdometry(loop, lambda: wakes.append(1))
    got, woken = loop.on_message("goal", goal, 0.0), 0
    for topic, msg in _arrivals():     # what the node's main thread sees of each arrival
        if topic == "odom":
            held.on_odom(msg)          # Zenoh's thread
            if wakes:                  # woken: a scan waited
                woken += len(wakes)
                wakes.clear()
                got += held.feed(0.0)
        else:
            got += held.feed(0.0) + loop.on_message(topic, msg, 0.0) + held.after(0.0)
    assert [t for t, _ in got].count("cmd_vel") == 12
    assert got == expected
    assert not loop.pending and not held.kept
    assert woken == 4 * 5   # only the 4 scans that came first, by each of their 5 odometries (of 56)


def test_odometry_arriving_while_a_scan_waits_wakes_the_main_thread():
    loop, wakes = PlannerLoop(make_planner("apf")), []
    held = HeldOdometry(loop, lambda: wakes.append(1))
    loop.on_message("goal", Goal(stamp_ns=0, x=5.0, y=0.0), 0.0)
    held.on_odom(_odom(0))
    assert not wakes                   # nothing waits: kept, no wake
    assert held.feed(0.0) == [] and not held.kept
    assert loop.on_message("scan", _scan(DT * 5), 0.0) == []   # waits for odom(100 ms)
    held.on_odom(_odom(DT * 4))
    assert wakes == [1]
    held.on_odom(_odom(DT * 5))
    out = held.feed(0.0)
    assert [t for t, _ in out][0] == "cmd_vel" and out[0][1].stamp_ns == DT * 5
