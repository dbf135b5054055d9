"""Run outcome and figures are decided at an exact sim time (papf.launch.outcome)."""

import math
from unittest.mock import MagicMock

from papf.launch.outcome import NS, RunMonitor
from papf.launch.sequence import RunSequence
from schemas import BatteryState, Clock, Event, Keys, Odometry, PlannerStatus, Twist


def pose(t_s, x, v=0.2):
    return Odometry(stamp_ns=int(t_s * NS), x=x, y=0.0, yaw=0.0, v=v, w=0.0)


def battery(t_s, mah):
    return BatteryState(stamp_ns=int(t_s * NS), voltage=12.0, current=1.0, power=12.0,
                        charge_used_mAh=mah, energy_J=mah * 43.2)


def test_reached_takes_figures_at_t_end_not_later():
    m = RunMonitor(timeout_s=100)
    for i in range(11):
        m.on_pose(pose(i, 0.1 * i, v=0.0 if i == 0 else 0.1))
        m.on_battery(battery(i, float(i)))
    m.on_status(PlannerStatus(stamp_ns=5 * NS, state="reached"))
    assert m.done and m.outcome == "reached" and m.figures_complete()
    r = m.result("apf", "open", 1, wall_time_s=2.0)
    assert math.isclose(r.path_length_m, 0.5) and r.charge_mAh == 5.0
    assert r.sim_time_s == 5.0 and r.duration_s == 4.0 and r.exit_code == 0


def test_figures_wait_until_samples_reach_t_end():
    m = RunMonitor(timeout_s=100)
    m.on_pose(pose(1, 0.1))
    m.on_battery(battery(1, 1.0))
    m.on_status(PlannerStatus(stamp_ns=2 * NS, state="stagnated", reason="no progress"))
    assert not m.figures_complete()
    m.on_pose(pose(2, 0.2))
    m.on_battery(battery(2, 2.0))
    assert m.figures_complete()
    r = m.result("apf", "w", 0, 0)
    assert (r.outcome, r.exit_code, r.reason) == ("stagnated", 3, "no progress")


def test_timeout_at_exact_sim_time():
    m = RunMonitor(timeout_s=3)
    m.on_clock(Clock(stamp_ns=2 * NS))
    assert not m.done
    m.on_clock(Clock(stamp_ns=3 * NS + 20_000_000))
    assert m.outcome == "timeout" and m.t_end_ns == 3 * NS
    assert m.result("apf", "w", 0, 0).exit_code == 5


def test_sim_pose_stamps_stand_for_the_clock_in_sim():
    """In sim the launcher takes sim time from sim/pose (put just before clock at every
    instant): the same timeout, t_end and clock as from the clock messages."""
    session = MagicMock()
    seq = RunSequence(session, Keys("rosbot"), MagicMock(), RunMonitor(timeout_s=3))
    assert "clock" not in seq._handlers and "sim/pose" in seq._handlers
    for t in (2 * NS, 3 * NS + 20_000_000):
        seq._handlers["sim/pose"](Odometry(stamp_ns=t, x=0.0, y=0.0, yaw=0.0, v=0.0, w=0.0))
    by_clock = RunMonitor(timeout_s=3)
    for t in (2 * NS, 3 * NS + 20_000_000):
        by_clock.on_clock(Clock(stamp_ns=t))
    assert (seq.monitor.outcome, seq.monitor.t_end_ns, seq.monitor.clock_ns) == (
        by_clock.outcome, by_clock.t_end_ns, by_clock.clock_ns) == ("timeout", 3 * NS, 3 * NS + 20_000_000)
    on_robot = RunSequence(session, Keys("rosbot"), MagicMock(), RunMonitor(timeout_s=3), "odom")
    assert "clock" in on_robot._handlers


def test_collision_ends_run_and_is_counted():
    m = RunMonitor(timeout_s=10)
    m.on_event(Event(stamp_ns=NS, kind="collision", source="base_driver", x=1, y=2))
    assert m.outcome == "collision"
    m.on_status(PlannerStatus(stamp_ns=2 * NS, state="reached"))
    assert m.outcome == "collision" and m.result("p", "w", 0, 0).collisions == 1


def test_collisions_can_be_counted_without_stopping():
    m = RunMonitor(timeout_s=10, stop_on_collision=False)
    m.on_event(Event(stamp_ns=NS, kind="collision", source="base_driver"))
    assert not m.done
    m.on_status(PlannerStatus(stamp_ns=2 * NS, state="reached"))
    assert m.outcome == "reached" and m.result("p", "w", 0, 0).collisions == 1


def test_earlier_outcome_wins():
    m = RunMonitor(timeout_s=10)
    m.on_status(PlannerStatus(stamp_ns=5 * NS, state="reached"))
    m.on_event(Event(stamp_ns=4 * NS, kind="collision", source="base_driver"))
    assert m.outcome == "collision" and m.t_end_ns == 4 * NS


def test_stop_latency_after_fault():
    m = RunMonitor(timeout_s=10)
    m.on_cmd(Twist(stamp_ns=NS, v=0.2, w=0))
    m.on_event(Event(stamp_ns=NS + 500_000_000, kind="watchdog_stop", source="base_driver"))
    m.fail("planner exited with code -9")
    r = m.result("p", "w", 0, 0)
    assert r.outcome == "failed" and r.exit_code == 6 and r.stop_latency_s == 0.5
    assert "stop_latency_s" in r.to_json()


def test_node_faults_are_reported():
    m = RunMonitor(timeout_s=10)
    assert "faults" not in m.result("p", "w", 0, 0).to_json()
    m.on_event(Event(stamp_ns=NS, kind="node_fault", source="base_driver",
                     detail="no cmd_vel for 2 s; free-running"))
    assert m.result("p", "w", 0, 0).to_json()["faults"] == [
        "base_driver at 1.00 s: no cmd_vel for 2 s; free-running"]


def test_stop_latency_ignores_an_outage_the_run_recovered_from():
    m = RunMonitor(timeout_s=100)
    m.on_event(Event(stamp_ns=2 * NS, kind="watchdog_stop", source="base_driver"))
    m.on_cmd(Twist(stamp_ns=9 * NS, v=0.2, w=0))  # commands resumed after the outage
    m.on_status(PlannerStatus(stamp_ns=20 * NS, state="reached"))
    assert m.result("p", "w", 0, 0).stop_latency_s is None


def test_every_reached_claim_is_judged_even_when_a_later_one_came_first():
    """Statuses and poses travel on different links: two claims may both arrive before the
    pose of the first. Each is judged by its own pose; the earliest accepted decides."""
    m = RunMonitor(timeout_s=60, goal=(1.0, 0.0, 0.1))
    for t in (9 * NS, 9 * NS + 100_000_000):
        m.on_status(PlannerStatus(stamp_ns=t, state="reached", reason="near"))
    assert not m.done
    for k in range(10):
        t = 9 * NS + k * 20_000_000
        m.on_pose(Odometry(stamp_ns=t, x=0.95, y=0.0, yaw=0.0, v=0.0, w=0.0))
    assert m.outcome == "reached" and m.t_end_ns == 9 * NS
