"""The real-robot base driver (rosbot mode) and the ROSbot emulator: bridge keys, odometry,
kinematics, watchdog (pure, fake sessions)."""

from __future__ import annotations

import logging
import math
import queue

import pytest

from common import ros2
from common.drive import RosbotLimits
from common.errors import ConfigError
from common.ros_link import BridgeTopics
from nodes.base_driver.rosbot import (
    EFFECTIVE_TRACK,
    MASS,
    WHEEL_RADIUS,
    YAW_INERTIA,
    OdomFrame,
    Pose2D,
    RobotOdom,
    cdr_to_robot_odom,
    cdr_to_twist,
    compose,
    inverse,
    wheel_states,
)
from nodes.base_driver.rosbot_node import ZERO_HOLD_NS, RosbotDriver
from papf.robot.emulator import EmulatedRosbot
from schemas import Clock, Event, Odometry, Twist

MS = 1_000_000


# -- pure pieces --------------------------------------------------------------------------------
def test_bridge_keys_and_separation():
    t = BridgeTopics("robot1")
    assert t.keys == {"cmd_vel": "robot1/cmd_vel", "odometry": "robot1/odometry/filtered",
                      "battery": "robot1/battery", "scan": "robot1/scan"}
    assert BridgeTopics().key("/cmd_vel") == "cmd_vel"
    t.check_separate("rosbot")
    with pytest.raises(ConfigError, match="overlaps our namespace 'rosbot'"):
        BridgeTopics("rosbot").check_separate("rosbot")
    with pytest.raises(ConfigError, match="overlaps"):
        BridgeTopics("lab").check_separate("lab")


def test_odom_frame_rebases_on_the_world_start():
    frame = OdomFrame(Pose2D(1.0, 2.0, math.pi / 2))
    frame.anchor(Pose2D(5.0, 5.0, math.pi))       # the EKF's pose when the run starts
    start = frame.to_world(RobotOdom(0, Pose2D(5.0, 5.0, math.pi), 0.0, 0.0), 7)
    assert start.stamp_ns == 7
    assert (start.x, start.y, start.yaw) == pytest.approx((1.0, 2.0, math.pi / 2))
    ahead = frame.to_world(RobotOdom(0, Pose2D(4.0, 5.0, math.pi), 0.3, 0.1), 8)  # 1 m forward
    assert (ahead.x, ahead.y) == (pytest.approx(1.0), pytest.approx(3.0))
    assert (ahead.v, ahead.w) == (0.3, 0.1)
    p = Pose2D(0.3, -0.2, 0.7)
    q = compose(inverse(p), p)
    assert q.x == pytest.approx(0.0, abs=1e-12) and q.yaw == pytest.approx(0.0, abs=1e-12)


def test_wheel_states_kinematics_and_forces():
    prev = Odometry(stamp_ns=0, x=0, y=0, yaw=0, v=0.2, w=0.5)
    now = Odometry(stamp_ns=20 * MS, x=0, y=0, yaw=0, v=0.22, w=0.58)
    ws = wheel_states(prev, now)
    left, right = (0.22 - 0.58 * EFFECTIVE_TRACK / 2) / WHEEL_RADIUS, \
                  (0.22 + 0.58 * EFFECTIVE_TRACK / 2) / WHEEL_RADIUS
    assert ws.stamp_ns == now.stamp_ns
    assert ws.speed == pytest.approx((left, right, left, right))
    forces = [t / WHEEL_RADIUS for t in ws.torque]
    assert sum(forces) == pytest.approx(MASS * 1.0)                    # a = 0.02 / 0.02 s
    yaw_moment = (forces[1] + forces[3] - forces[0] - forces[2]) * EFFECTIVE_TRACK / 2
    assert yaw_moment == pytest.approx(YAW_INERTIA * 4.0)              # beta = 0.08 / 0.02 s
    assert wheel_states(None, now).torque == (0.0, 0.0, 0.0, 0.0)


def test_emulator_integrates_arcs_with_the_robot_limits():
    robot = EmulatedRosbot(cmd_timeout_s=0.0)
    robot.command(5.0, 0.5, 0)                   # clamped to 0.9 m/s, ramped at 1 m/s^2
    for k in range(1, 151):
        robot.step(k * 20 * MS, 0.02)
    assert robot.v == pytest.approx(0.9) and robot.w == pytest.approx(0.5)
    assert robot.pose.yaw == pytest.approx(0.5 * (3.0 - 0.06), abs=0.01)  # w reaches 0.5 in 6 steps
    timed = EmulatedRosbot(cmd_timeout_s=0.5)
    timed.command(0.3, 0.0, 0)
    for k in range(1, 60):
        timed.step(k * 20 * MS, 0.02)
    assert timed.v == 0.0                        # its own cmd_vel_timeout stopped it
    data = timed.odometry_cdr(123)
    assert cdr_to_robot_odom(data).pose.x == pytest.approx(timed.pose.x)


# -- the driver's logic with a fake node (no network, synthetic monotonic time) -----------------
class _Pub:
    def __init__(self):
        self.puts = []

    def put(self, data):
        self.puts.append(cdr_to_twist(data))

    def undeclare(self):
        pass


class _FakeNode:
    def __init__(self):
        self.pub = _Pub()
        self.session = type("S", (), {"declare_publisher": lambda _s, key: self.pub})()
        self.log = logging.getLogger("fake")
        self.published = []
        self.inbox, self.stop = queue.Queue(), False

    def publish(self, topic, msg):
        self.published.append((topic, msg))

    def of(self, topic):
        return [m for t, m in self.published if t == topic]


def _driver():
    node = _FakeNode()
    d = RosbotDriver(node, BridgeTopics(), RosbotLimits(), 20 * MS, OdomFrame())
    return node, d


def test_watchdog_zero_then_silence():
    node, d = _driver()
    d.on_tick(0)
    assert node.pub.puts == []                   # never commanded: leaves the robot alone
    d.on_command(Twist(stamp_ns=0, v=0.5, w=0.0), 0)
    t = 0
    while t < 400 * MS:
        t += 20 * MS
        d.on_tick(t)
    assert node.pub.puts[-1][0] == pytest.approx(0.4)          # ramped at 1 m/s^2
    assert d.watchdog_due() == 500 * MS + 1
    t = 500 * MS + 1
    d.send(t)
    assert [e.kind for e in node.of("events")] == ["watchdog_stop"]
    n_before = len(node.pub.puts)
    while t < 2_500 * MS:
        t += 20 * MS
        d.on_tick(t)
    speeds = [v for v, _ in node.pub.puts[n_before - 1:]]
    assert all(b <= a for a, b in zip(speeds, speeds[1:], strict=False)) and speeds[-1] == 0.0
    zeros = [v for v, _ in node.pub.puts if v == 0.0]
    assert len(zeros) <= ZERO_HOLD_NS // (20 * MS) + 2          # zeros for ~1 s, then silence
    assert len(node.of("events")) == 1


def test_a_stopping_driver_brings_a_moving_robot_to_rest_at_its_limits(monkeypatch):
    node, d = _driver()
    clock = [0]
    monkeypatch.setattr("nodes.base_driver.rosbot_node.time.monotonic_ns", lambda: clock[0])
    monkeypatch.setattr("nodes.base_driver.rosbot_node.time.sleep",
                        lambda s: clock.__setitem__(0, clock[0] + round(s * 1e9)))
    for t in range(0, 800 * MS, 20 * MS):       # commanded every tick (no watchdog)
        d.on_command(Twist(stamp_ns=t, v=0.5, w=-1.0), t)
        d.on_tick(t)
    clock[0] = 780 * MS                  # the last tick's time
    assert node.pub.puts[-1] == (pytest.approx(0.5), pytest.approx(-1.0))
    n = len(node.pub.puts)
    d.stop_robot()                       # the node is stopping while the robot drives
    ramp = node.pub.puts[n - 1:]
    steps = [abs(b[0] - a[0]) for a, b in zip(ramp, ramp[1:], strict=False)]
    assert max(steps) <= 1.0 * 0.020 + 1e-9                       # a_max, a tick at a time
    assert ramp[-1] == (0.0, 0.0) and ramp[-4] == (0.0, 0.0)      # then the exit's zeros
    assert clock[0] - 780 * MS <= 600 * MS                        # 0.5 s at 1 m/s^2, bounded
    assert [e.kind for e in node.of("events")] == []              # not a lost command


def test_run_clock_odometry_wheels_and_late_commands():
    node, d = _driver()
    d.on_bridge("odometry", ros2.encode(ros2.odometry(1, 3.0, 4.0, math.pi, 0.1, 0.0),
                                        ros2.ODOMETRY), 0)
    d.on_event(Event(stamp_ns=0, kind="run_started", source="t"), 10 * MS)
    d.on_tick(10 * MS)
    odom, = node.of("odom")
    assert odom.stamp_ns == 0                                                # anchored at start
    assert (odom.x, odom.y, odom.yaw) == pytest.approx((0.0, 0.0, 0.0), abs=1e-12)
    assert node.of("wheels")[0].stamp_ns == 0 and node.of("clock") == [Clock(stamp_ns=0)]
    d.on_command(Twist(stamp_ns=0, v=0.3, w=0.0), 900 * MS)                  # 0.89 s late
    assert d.late == 1 and node.pub.puts == []
    d.on_command(Twist(stamp_ns=800 * MS, v=0.3, w=0.0), 900 * MS)
    assert len(node.pub.puts) == 1
    d.tick = 50                                   # odometry stopped arriving 1 s ago
    d.on_tick(1_010 * MS)
    assert len(node.of("odom")) == 1 and node.of("events")[-1].kind == "node_fault"
    d.on_bridge("battery", ros2.encode(ros2.battery_state(1, 11.9), ros2.BATTERY_STATE), 0)
    d.on_bridge("battery", b"garbage", 0)
    assert d.bad["battery"] == 1


def test_odometry_between_runs_for_teleop():
    node, d = _driver()
    odom_cdr = ros2.encode(ros2.odometry(1, 1.0, 2.0, 0.0, 0.2, 0.0), ros2.ODOMETRY)
    for k in range(1, 11):                              # 200 ms of ticks before any run
        d.on_bridge("odometry", odom_cdr, k * 20 * MS)
        d.on_tick(k * 20 * MS)
    idle = node.of("odom")
    assert len(idle) == 2 and all(o.stamp_ns == 0 and o.x == pytest.approx(1.0) for o in idle)
    assert node.of("wheels") == [] and node.of("clock") == []   # no run: no clock, no energy


def test_odometry_after_a_run_never_repeats_a_stamp():
    """A recording that goes on after ``run_ended`` holds each odom stamp once, in order."""
    node, d = _driver()
    odom_cdr = ros2.encode(ros2.odometry(1, 1.0, 2.0, 0.0, 0.0, 0.0), ros2.ODOMETRY)
    d.on_bridge("odometry", odom_cdr, 0)
    d.on_event(Event(stamp_ns=0, kind="run_started", source="test"), 0)
    now = 0
    for now in range(20 * MS, 400 * MS, 20 * MS):
        d.on_bridge("odometry", odom_cdr, now)
        d.next_tick_at(now)                             # the loop's tick grid
        d.on_tick(now)
    end = now
    d.on_event(Event(stamp_ns=0, kind="run_ended", source="test"), end)
    for now in range(end + 20 * MS, end + 600 * MS, 20 * MS):   # idle: 10 Hz odometry
        d.on_bridge("odometry", odom_cdr, now)
        d.on_tick(now)
    stamps = [o.stamp_ns for o in node.of("odom")]
    assert len(stamps) > 20 and stamps == sorted(stamps) and len(set(stamps)) == len(stamps)


def test_stop_wake_up_is_not_a_robot_message():
    """Ctrl-C puts ``(None, None)`` in the inbox to wake the loop: the driver just stops."""
    node, d = _driver()

    class _StopWhenWoken:
        def __bool__(self):
            return node.inbox.empty()

    node.stop = _StopWhenWoken()
    node.inbox.put((None, None))
    d.run()                                            # returned: no TypeError from a None
    assert d.bad == {}
