"""Driving over a slow link, robot side: the plan follower, the collision monitor, the link
statistics and their join (docs/link-driving.md); the laptop's link watch, which names the link
in the reason of a run that ended after an outage. Pure cores, time passed in."""

from __future__ import annotations

import math

import numpy as np
import pytest

from common.drive import unicycle
from common.errors import ConfigError
from common.linkstats import LinkStats, summary
from nodes.base_driver.follow import (
    MAX_TRACKING_ERROR_M,
    FollowSettings,
    PlanFollower,
    age_scale,
    reference,
)
from nodes.base_driver.link_drive import LinkDriving, scan_points
from nodes.base_driver.monitor import CollisionMonitor, MonitorSettings
from nodes.planner.registry import make_planner
from nodes.planner.rollout import rollout
from papf.launch.linkwatch import LinkWatch
from schemas import Odometry, Scan, Twist
from tests.support.cli import papf

MS = 1_000_000
W = 500 * MS          # the driver's watchdog


S = 1_000_000_000   # [ns]


def straight_plan(stamp_ns: int, v: float = 0.5, x0: float = 0.0, steps: int = 15,
                  dt_ns: int = 100 * MS) -> Twist:
    poses = []
    for k in range(steps + 1):
        poses += (x0 + v * k * dt_ns * 1e-9, 0.0, 0.0)
    return Twist(stamp_ns=stamp_ns, v=v, w=0.0, plan=tuple(poses), plan_dt_ns=dt_ns)


# -- the follower ---------------------------------------------------------------------------------
def test_a_plan_older_than_the_watchdog_is_followed_while_the_robot_sees_for_itself():
    f = PlanFollower(W)
    cmd = straight_plan(stamp_ns=1_000 * MS)
    assert f.take(cmd, 1_700 * MS, monitor_fresh=True) == ("obeyed", "")   # 0.7 s old
    v, w, why, scale = f.target(1_750 * MS, (0.375, 0.0, 0.0), monitor_fresh=True)
    assert why == "" and v == pytest.approx(0.5 * scale, abs=1e-6) and abs(w) < 1e-9
    assert scale == pytest.approx(age_scale(0.75, 1.5)) and scale < 1.0


def test_without_its_own_scan_the_robot_obeys_no_plan_older_than_the_watchdog():
    f = PlanFollower(W)
    verdict, why = f.take(straight_plan(stamp_ns=1_000 * MS), 1_700 * MS, monitor_fresh=False)
    assert verdict == "late" and "0.700 s old" in why
    assert f.take(straight_plan(stamp_ns=1_300 * MS), 1_700 * MS, monitor_fresh=False)[0] == "obeyed"
    assert f.target(1_801 * MS, (0.0, 0.0, 0.0), monitor_fresh=False).why  # 0.501 s: ran out


@pytest.mark.parametrize("arrived_ms, t_ms, reason", [(1_700, 2_201, "no command for"),
                                                      (2_400, 2_501, "ran out")])
def test_nothing_is_obeyed_past_the_watchdog_or_the_plans_validity(arrived_ms, t_ms, reason):
    f = PlanFollower(W, FollowSettings(max_plan_age=1.5))
    cmd = straight_plan(stamp_ns=1_000 * MS, steps=30)
    assert f.take(cmd, arrived_ms * MS, True)[0] == "obeyed"
    on_plan = reference(cmd, (t_ms - 2) * MS)[:3]
    assert not f.target((t_ms - 2) * MS, on_plan, True).why
    target = f.target(t_ms * MS, on_plan, True)
    assert (target.v, target.w) == (0.0, 0.0) and reason in target.why


def test_an_older_command_never_replaces_a_fresher_one_but_a_stop_always_counts():
    f = PlanFollower(W)
    f.take(straight_plan(stamp_ns=1_000 * MS), 1_300 * MS, True)
    assert f.take(straight_plan(stamp_ns=900 * MS), 1_310 * MS, True)[0] == "stale"
    assert f.take(Twist(stamp_ns=1_000 * MS, v=0.0, w=0.0), 1_320 * MS, True)[0] == "obeyed"
    assert f.target(1_330 * MS, (0.0, 0.0, 0.0), True)[:2] == (0.0, 0.0)


@pytest.mark.parametrize("plan, dt", [((0.0, 0.0, 0.0), 100 * MS), ((0.0,) * 7, 100 * MS),
                                      ((0.0,) * 6, 5 * MS), ((0.0,) * 6, 0)])
def test_a_malformed_plan_is_refused(plan, dt):
    assert PlanFollower(W).take(Twist(stamp_ns=0, v=0.1, w=0.0, plan=plan, plan_dt_ns=dt),
                                100 * MS, True)[0] == "late"


def test_a_command_stamped_in_the_future_is_refused_beyond_the_watchdog():
    assert PlanFollower(W).take(straight_plan(stamp_ns=2_000 * MS), 1_000 * MS, True)[0] == "late"
    f = PlanFollower(W)      # a tool's clock a little ahead of the robot's: fresh
    assert f.take(Twist(stamp_ns=1_050 * MS, v=0.4, w=0.2), 1_000 * MS, True)[0] == "obeyed"
    assert f.target(1_400 * MS, None, True)[:2] == (0.4, 0.2)


def test_the_follower_corrects_towards_the_plan_and_never_outruns_it():
    f = PlanFollower(W)
    f.take(straight_plan(stamp_ns=0, v=0.3), 100 * MS, True)
    behind = f.target(200 * MS, (0.0, 0.0, 0.0), True)        # reference at x = 0.06
    left = f.target(200 * MS, (0.06, 0.1, 0.0), True)         # 0.1 m left of it
    assert behind.v <= 0.3 + 1e-9 and behind.v > 0.0          # catches up, capped at the plan's
    assert left.w < 0.0                                        # steers back right
    far = f.target(200 * MS, (0.06, MAX_TRACKING_ERROR_M + 0.1, 0.0), True)
    assert (far.v, far.w) == (0.0, 0.0) and "not chased" in far.why


def test_following_a_rolled_out_plan_with_delay_ends_where_the_plan_goes():
    """A planner's rollout, 0.6 s old when it arrives, driven by the follower in closed loop
    from where the robot really is: the robot ends on the plan's path, not beside it."""
    planner = make_planner("apf", None, ["v_max=0.5"])
    from nodes.planner.field import speed_ref

    apf = planner.apf
    poses = rollout(0.0, 0.0, 0.0, 0.4, lambda err: speed_ref(10.0, err, apf), apf, 0.1, 15)
    cmd = Twist(stamp_ns=0, v=0.0, w=0.0, plan=poses, plan_dt_ns=100 * MS)
    f = PlanFollower(W)
    f.take(cmd, 600 * MS, True)
    x, y, yaw = reference(cmd, 600 * MS)[:3]      # the robot drove the first 0.6 s of it
    for t in range(600, 1100, 20):          # within the watchdog of its arrival
        v, w, why, _ = f.target(t * MS, (x, y, yaw), True)
        assert not why
        x, y, yaw = unicycle(x, y, yaw, v, w, 0.02)
    path = [reference(cmd, t * MS)[:2] for t in range(0, 1500, 5)]
    assert min(math.hypot(px - x, py - y) for px, py in path) < 0.01     # on the path
    assert x > reference(cmd, 800 * MS)[0]          # and along it (slower: the plan is old)


def test_the_age_scale_falls_from_one_to_a_quarter():
    assert age_scale(0.1, 1.5) == 1.0 and age_scale(1.5, 1.5) == pytest.approx(0.25)
    assert age_scale(0.6, 1.5) > age_scale(1.0, 1.5)


@pytest.mark.parametrize("bad", [0.0, 2.5, math.nan, math.inf])
def test_the_plan_age_has_a_range_that_keeps_the_watchdog_meaningful(bad):
    with pytest.raises(ConfigError):
        FollowSettings(max_plan_age=bad)


# -- the collision monitor ----------------------------------------------------------------------
def wall_monitor(x: float, **kw) -> CollisionMonitor:
    m = CollisionMonitor(MonitorSettings(**kw))
    m.scan(0, np.array([[x, y] for y in np.linspace(-0.5, 0.5, 21)]), (0.0, 0.0, 0.0))
    return m


def test_a_return_in_the_stop_zone_stops_forward_motion_but_not_backing_away():
    m = wall_monitor(0.13)                                     # 3 cm ahead of the front face
    assert m.check(0.5, 0.0, (0.0, 0.0, 0.0)).v == 0.0
    assert m.check(-0.2, 0.0, (0.0, 0.0, 0.0)).v == -0.2


def test_the_monitor_slows_the_robot_as_a_return_comes_closer():
    far, near = wall_monitor(1.0), wall_monitor(0.45)
    v_far = far.check(0.5, 0.0, (0.0, 0.0, 0.0)).v
    v_near = near.check(0.5, 0.0, (0.0, 0.0, 0.0)).v
    assert v_far == 0.5 and 0.0 <= v_near < 0.5
    # the robot drove on since the scan: the same return, seen from closer, slows it more
    assert far.check(0.5, 0.0, (0.55, 0.0, 0.0)).v == pytest.approx(v_near)


def test_turning_in_place_is_refused_when_the_body_would_sweep_a_return():
    m = CollisionMonitor()
    m.scan(0, np.array([[0.0, 0.17]]), (0.0, 0.0, 0.0))        # beside the robot
    assert m.check(0.0, 1.0, (0.0, 0.0, 0.0)).w == 0.0
    assert m.check(0.0, 1.0, (1.0, 0.0, 0.0)).w == 1.0         # far from it: free


@pytest.mark.parametrize("name, bad", [("stop_margin", 0.0), ("stop_margin", -1.0),
                                       ("time_before_collision", 0.0),
                                       ("time_before_collision", math.inf),
                                       ("scan_timeout", 0.0), ("scan_timeout", math.nan)])
def test_no_monitor_setting_in_range_switches_it_off(name, bad):
    with pytest.raises(ConfigError):
        MonitorSettings(**{name: bad})


def test_a_scan_is_fresh_only_for_its_timeout():
    m = wall_monitor(1.0, scan_timeout=0.5)
    assert m.fresh(500 * MS) and not m.fresh(501 * MS) and not CollisionMonitor().fresh(0)


# -- link statistics ----------------------------------------------------------------------------
def test_round_trips_late_commands_and_an_outage_with_its_length():
    s = LinkStats("robot", W)
    for k in range(10):
        assert s.command(k * 100 * MS + 600 * MS, k * 100 * MS, "obeyed") == []
    assert s.tick(1_300 * MS) == []
    assert s.tick(2_000 * MS) == []                 # the last came at 1.5 s
    lost = s.tick(2_001 * MS)
    assert [k for k, _ in lost] == ["link_lost"] and s.tick(2_100 * MS) == []
    back = s.command(3_500 * MS, 2_900 * MS, "late")
    assert back[0][0] == "link_restored" and "2.00 s" in back[0][1]
    h = s.report(3_600 * MS)
    assert (h.commands, h.obeyed, h.late, h.outages) == (11, 10, 1, 1)
    assert h.rtt_p50_ms == pytest.approx(600.0) and h.longest_outage_s == pytest.approx(2.0)
    j = summary(h)
    assert j["late_commands"] == 1 and j["outages"] == 1 and j["rtt_p99_ms"] == 600.0


def test_an_outage_still_going_counts_up_to_now():
    s = LinkStats("laptop", W)
    s.heard(0)
    s.tick(600 * MS)
    h = s.report(3_000 * MS)
    assert h.state == "lost" and h.outage_s == pytest.approx(3.0)


# -- the join -------------------------------------------------------------------------------------
def test_a_run_over_a_dead_link_stops_once_and_says_why():
    d = LinkDriving(W)
    d.scan(Scan(stamp_ns=0, angle_min=-math.pi, angle_increment=2 * math.pi / 8, range_min=0.2,
                range_max=10.0, ranges=np.full(8, np.inf, np.float32)), 0, (0.0, 0.0, 0.0))
    assert d.command(straight_plan(stamp_ns=0), 400 * MS) == []
    kinds = []
    for t in range(400, 2000, 20):
        d.scan(Scan(stamp_ns=t * MS, angle_min=0.0, angle_increment=0.1, range_min=0.2,
                    range_max=10.0, ranges=np.full(3, np.inf, np.float32)), t * MS, (0.0, 0.0, 0.0))
        v, w, events = d.control(t * MS, (0.0, 0.0, 0.0))
        kinds += [k for k, _ in events]
        if t > 900:
            assert (v, w) == (0.0, 0.0)
    assert kinds.count("watchdog_stop") == 1 and kinds.count("link_lost") == 1
    back = d.command(straight_plan(stamp_ns=100 * MS), 2_500 * MS)
    assert [k for k, _ in back] == ["link_restored", "command_refused"]
    assert "the robot stopped the base at 0.92 s (no command for 0.520 s" in back[0][1]


def test_scan_points_drop_invalid_returns_and_apply_the_sensor_offset():
    scan = Scan(stamp_ns=0, angle_min=0.0, angle_increment=math.pi / 2, range_min=0.2,
                range_max=5.0, ranges=np.array([1.0, np.inf, 0.1, np.nan], np.float32),
                sensor_x=0.02)
    assert scan_points(scan).tolist() == [[1.02, 0.0]]


def test_lockstep_commands_carry_no_plan_and_realtime_ones_do():
    from nodes.planner.loop import PlannerLoop
    from schemas import Goal

    for realtime, has_plan in ((False, False), (True, True)):
        loop = PlannerLoop(make_planner("apf", None, []), realtime=realtime)
        loop.on_message("goal", Goal(stamp_ns=0, x=3.0, y=0.0), 0.0)
        loop.on_message("odom", Odometry(stamp_ns=0, x=0.0, y=0.0, yaw=0.0, v=0.0, w=0.0), 0.0)
        out = loop.on_message("scan", Scan(stamp_ns=0, angle_min=-math.pi, angle_increment=0.1,
                                           range_min=0.2, range_max=10.0,
                                           ranges=np.full(63, np.inf, np.float32)), 0.0)
        cmd = dict(out)["cmd_vel"]
        assert bool(cmd.plan) is has_plan
        if has_plan:
            assert cmd.plan[:3] == (0.0, 0.0, 0.0) and len(cmd.plan) == 3 * 16


# -- the laptop's view: JSON, progress text, whom the reason blames --------------------------------
def robot_report(**kw):
    from schemas import LinkHealth

    base = dict(stamp_ns=10 * 10**9, side="robot", rtt_last_ms=600.0, rtt_p50_ms=590.0,
                rtt_p99_ms=700.0, commands=100, obeyed=95, late=5)
    return LinkHealth(**{**base, **kw})


def test_a_stagnation_while_the_commands_came_late_names_the_link_not_the_planner():
    from papf.launch.linkwatch import LinkWatch

    watch = LinkWatch()
    watch.heard(0)
    watch.on_health(robot_report(obeyed=20, late=80))
    why = watch.blame("stagnated", "no progress > 0.1 m towards the goal in 20.0 s", 10**9, 25.0)
    assert why.startswith("the link: 80 of 100 commands reached the robot too late")
    assert "no progress" in why
    assert watch.blame("reached", "within 0.1 m", 10**9, 25.0) is None
    silent = LinkWatch()                          # a driver that sends no reports: no blame
    silent.heard(0)
    assert silent.blame("stagnated", "no progress", 10**9, 25.0) is None


def test_a_healthy_link_leaves_the_planners_reason_alone_and_an_outage_is_named():
    from papf.launch.linkwatch import LinkWatch

    watch = LinkWatch()
    watch.heard(0)
    watch.on_health(robot_report())
    assert watch.blame("stagnated", "no progress", 10**9, 25.0) is None
    watch.tick(2 * 10**9)                                  # the robot went silent
    assert "an outage" in watch.blame("timeout", "no outcome within 30 s", 5 * 10**9, 30.0)
    assert watch.text() == "link LOST"
    assert watch.blame("failed", "interrupted", 5 * 10**9, 30.0) is None     # Ctrl-C stays 130
    assert watch.blame("failed", "sim time stuck at 3.00 s for 20 s", 5 * 10**9, 30.0)
    out = watch.summary(5 * 10**9)
    assert out["laptop_outages"] == 1 and out["laptop_outage_s"] == [5.0]
    assert out["rtt_p50_ms"] == 590.0 and out["late_commands"] == 5


def test_runs_on_one_host_have_no_link_in_their_json():
    from papf.launch.outcome import RunMonitor

    result = RunMonitor(10.0).result("papf", "energy", 0, 1.0)
    assert "link" not in result.to_json()
    result.link = {"rtt_p50_ms": 1.0}
    assert result.to_json()["link"] == {"rtt_p50_ms": 1.0}


def test_papf_topic_list_says_what_the_link_did():
    from papf.bus.decode import decode
    from papf.bus.topics import link_line

    d = decode("rosbot/link", robot_report(outages=1, outage_s=4.6).to_bytes())
    line = link_line("rosbot/link", d.value)
    assert line == ("link (rosbot/link, robot side): up, round trip p50 590 / p99 700 ms, "
                    "5 of 100 commands refused, 1 outages (4.6 s)")


def test_a_robot_that_stood_still_starts_an_old_plan_from_its_beginning():
    """The first plan arrives 1.2 s old, the robot still where the plan starts: it follows
    the plan from there (not stopping because the plan's point of 'now' is 0.6 m away)."""
    f = PlanFollower(W)
    cmd = straight_plan(stamp_ns=0, v=0.5)
    f.take(cmd, 1_200 * MS, True, pose=(0.0, 0.0, 0.0))
    target = f.target(1_220 * MS, (0.0, 0.0, 0.0), True)
    assert not target.why and target.v > 0.0
    kept_up = PlanFollower(W)                                  # where the plan says: no shift
    kept_up.take(cmd, 1_200 * MS, True, pose=reference(cmd, 1_200 * MS)[:3])
    assert kept_up.shift_ns == 0 and f.shift_ns == -1_200 * MS


def test_the_time_the_link_held_the_robot_still_is_reported_and_blamed():
    from papf.launch.linkwatch import LinkWatch

    d = LinkDriving(W)
    d.command(straight_plan(stamp_ns=0), 100 * MS, (0.0, 0.0, 0.0))
    for t in range(100, 3100, 20):
        d.control(t * MS, (0.0, 0.0, 0.0))
    held = d.health(3_100 * MS).held_s
    assert held == pytest.approx(2.58, abs=0.001)   # no scan of its own: valid 0.5 s from the stamp
    watch = LinkWatch()
    watch.heard(0)
    watch.on_health(robot_report(held_s=12.0))
    assert "stood 12.0 s of 30.0 s" in watch.blame("stagnated", "no progress", 10**9, 30.0)


@pytest.mark.parametrize("argv, says", [
    (["run", "--world", "energy", "--robot-record", "r.mcap"], "add --link"),
    (["run", "--world", "energy", "--link", "lan", "--robot-record", "/no/such/dir/r.mcap"],
     "does not exist"),
    (["launch", "robot", "--record", "/no/such/dir/r.mcap"], "does not exist"),
])
def test_the_robots_recording_is_checked_before_anything_starts(argv, says, tmp_path):

    out = papf(*argv, timeout=60, cwd=tmp_path)
    assert out.returncode == 2, out.stderr
    assert says in out.stderr and len(out.stderr.strip().splitlines()) == 1, out.stderr


@pytest.mark.parametrize("option", ["--max-plan-age=0", "--max-plan-age=nan", "--stop-margin=0",
                                    "--time-before-collision=inf", "--scan-timeout=5"])
def test_the_drivers_link_settings_refuse_values_that_would_switch_safety_off(option):
    import subprocess
    import sys

    out = subprocess.run([sys.executable, "-m", "nodes.base_driver", "--driver", "rosbot",
                          option], capture_output=True, text=True, timeout=60)
    assert out.returncode == 2 and option.split("=")[0] in out.stderr, out.stderr


def test_a_run_ended_after_an_outage_the_laptop_heard_names_the_link():
    watch = LinkWatch()
    watch.heard(0)
    watch.heard(20 * S)
    watch.tick(21 * S + 100)                                      # silent since 20 s: lost
    watch.heard(41 * S)                                           # back after 21 s
    reason = watch.blame("stagnated", "no progress", 42 * S, 42.0)
    assert reason is not None and reason.startswith("the link: nothing from the robot for 21.0 s")
    assert "(what the run saw: no progress)" in reason


def test_a_short_blip_is_not_blamed():
    watch = LinkWatch()
    watch.heard(0)
    watch.tick(2 * S)                                             # 2 s lost of a 100 s run
    watch.heard(2 * S + 100)
    assert watch.blame("stagnated", "no progress", 100 * S, 100.0) is None
