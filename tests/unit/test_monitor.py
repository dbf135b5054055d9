"""Run outcome and figures are decided at an exact sim time (papf.launch.outcome)."""

import json
import math
import tracemalloc
from unittest.mock import MagicMock

from papf.launch.outcome import NS, RunMonitor, RunResult
from papf.launch.sequence import RunSequence, where_held
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


def pose_at(t_s, x, y=0.0, v=0.2):
    return Odometry(stamp_ns=round(t_s * NS), x=x, y=y, yaw=0.0, v=v, w=0.0)


def battery_at(t_s, mah):
    return BatteryState(stamp_ns=round(t_s * NS), voltage=12.0, current=1.0, power=12.0,
                        charge_used_mAh=mah, energy_J=mah * 43.2)


def test_reached_is_judged_from_ground_truth_not_the_planners_word():
    m = RunMonitor(timeout_s=100, goal=(5.0, 0.0, 0.1))
    m.on_pose(pose_at(0.0, 0.0))
    m.on_status(PlannerStatus(stamp_ns=0, state="reached"))   # forged: the robot is at 0 m
    assert not m.done and m.refuted_claims == 1
    m.on_pose(pose_at(1.0, 4.95))
    m.on_status(PlannerStatus(stamp_ns=NS, state="reached"))   # true: 5 cm from the goal
    assert m.outcome == "reached" and m.t_end_ns == NS


def test_a_reached_claim_waits_for_the_pose_of_its_instant():
    m = RunMonitor(timeout_s=100, goal=(1.0, 0.0, 0.1))
    m.on_pose(pose_at(0.98, 0.5))
    m.on_status(PlannerStatus(stamp_ns=NS, state="reached"))
    assert not m.done                      # the pose of t = 1 s has not arrived yet
    m.on_pose(pose_at(1.0, 0.95))
    assert m.outcome == "reached"


def test_figures_freeze_at_a_nodes_death_and_keep_the_timeout():
    m = RunMonitor(timeout_s=60)
    for i in range(200):                    # the meter dies after 12 s; the sim runs on
        m.on_pose(pose_at(i * 0.1, i * 0.01))
        if i <= 120:
            m.on_battery(battery_at(i * 0.1, i * 0.01))
    m.clock_ns = round(210.7 * NS)
    m.fail("energy_meter exited with code -9", at_ns=m.last_stamp("battery"))
    r = m.result("apf", "energy", 0, 1.0)
    assert r.outcome == "failed" and math.isclose(r.sim_time_s, 12.0)
    assert math.isclose(r.path_length_m, 1.2) and math.isclose(r.charge_mAh, 1.2)
    m2 = RunMonitor(timeout_s=60)
    m2.clock_ns = round(210.7 * NS)
    m2.fail("recorder exited with code 1")
    assert m2.t_end_ns == 60 * NS           # never past the timeout


def test_json_has_null_not_nan_for_a_missing_figure():
    m = RunMonitor(timeout_s=10)
    m.fail("planner exited with code 2")
    text = json.dumps(m.result("apf", "open", 0, 1.0).to_json(), allow_nan=False)
    assert json.loads(text)["charge_mAh"] is None and json.loads(text)["energy_J"] is None
    assert RunResult("failed", "apf", "w", 0, 0.0, 0.0, math.nan, math.inf, 0, 0.0, 0.0
                     ).to_json()["energy_J"] is None


def test_launcher_memory_stays_constant_over_a_long_run():
    m = RunMonitor(timeout_s=1e6, goal=(1e3, 0.0, 0.1))

    def feed(n0, n1):
        for i in range(n0, n1):
            t = i * 0.02
            m.on_pose(pose_at(t, t * 0.1))
            m.on_battery(battery_at(t, t))

    tracemalloc.start()
    feed(0, 20_000)                          # fill the windows (traced: what leaves is seen)
    before = tracemalloc.take_snapshot()
    feed(20_000, 120_000)                    # 2000 s more of sim time
    after = tracemalloc.take_snapshot()
    tracemalloc.stop()
    growth = sum(s.size_diff for s in after.compare_to(before, "filename"))
    assert growth < 64 * 1024, growth        # was ~34 KB per sim second: 68 MB here
    m._decide("timeout", round(2399.98 * NS), "")
    assert math.isclose(m.path_length_m(), 239.998, rel_tol=1e-6)


def test_a_held_lockstep_cycle_is_named_by_the_nodes_last_stamps():
    """``where_held``: each node's last stamps taken and put [s], and the nodes that did not
    answer — the one holding the cycle is the silent one, or the one that took the scan's
    stamp and put an older one."""
    health = {"planner": {"heard": {"scan": 47_100_000_000, "objects": 47_000_000_000},
                          "sent": {"cmd_vel": 47_000_000_000}},
              "lidar_sim": {"heard": {"sim/pose": 47_100_000_000}, "sent": {"scan": 47_100_000_000},
                            "peers": 3},
              "energy_meter": {"heard": {}, "sent": {}}}
    assert where_held(health, ["base_driver", "lidar_sim", "planner", "tracker", "energy_meter"]) == (
        "energy_meter nothing | lidar_sim (3 peer links) took sim/pose 47.10; put scan 47.10 | "
        "planner took objects 47.00, scan 47.10; put cmd_vel 47.00 | no answer from base_driver, "
        "tracker")
    assert where_held({}) == "no node answered"
