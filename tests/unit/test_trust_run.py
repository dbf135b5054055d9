"""Issue "trust no input", items 3, 4, 6-10: outcomes from ground truth, goals only from
the run that set them, honest ends, and every bad argument refused before anything
starts (exit 2, one line, no process)."""

from __future__ import annotations

import json
import math
import socket
import tracemalloc

import pytest

from common import runauth
from common.errors import ConfigError, WorldError
from nodes.planner.loop import PlannerLoop
from nodes.planner.registry import make_planner
from papf.launch.outcome import NS, RunMonitor, RunResult
from schemas import BatteryState, Goal, Odometry, PlannerStatus
from schemas.keys import Keys
from tests.support.cli import papf
from worlds import load_world, parse_world
from worlds.checks import check_runnable


def pose(t_s, x, y=0.0, v=0.2):
    return Odometry(stamp_ns=round(t_s * NS), x=x, y=y, yaw=0.0, v=v, w=0.0)


def battery(t_s, mah):
    return BatteryState(stamp_ns=round(t_s * NS), voltage=12.0, current=1.0, power=12.0,
                        charge_used_mAh=mah, energy_J=mah * 43.2)


# -- item 3 --------------------------------------------------------------------------------------
def test_reached_is_judged_from_ground_truth_not_the_planners_word():
    m = RunMonitor(timeout_s=100, goal=(5.0, 0.0, 0.1))
    m.on_pose(pose(0.0, 0.0))
    m.on_status(PlannerStatus(stamp_ns=0, state="reached"))   # forged: the robot is at 0 m
    assert not m.done and m.refuted_claims == 1
    m.on_pose(pose(1.0, 4.95))
    m.on_status(PlannerStatus(stamp_ns=NS, state="reached"))   # true: 5 cm from the goal
    assert m.outcome == "reached" and m.t_end_ns == NS


def test_a_reached_claim_waits_for_the_pose_of_its_instant():
    m = RunMonitor(timeout_s=100, goal=(1.0, 0.0, 0.1))
    m.on_pose(pose(0.98, 0.5))
    m.on_status(PlannerStatus(stamp_ns=NS, state="reached"))
    assert not m.done                      # the pose of t = 1 s has not arrived yet
    m.on_pose(pose(1.0, 0.95))
    assert m.outcome == "reached"


def test_planner_accepts_a_goal_only_from_the_run_that_set_it():
    key = bytes.fromhex(runauth.new_key())
    loop = PlannerLoop(make_planner("apf"), run_key=key)
    forged = Goal(stamp_ns=0, x=-5.0, y=3.0)
    assert loop.on_message("goal", forged, 0.0) == [] and loop.rejected_goals == 1
    assert loop.planner.goal is None
    other_run = runauth.sign(Goal(stamp_ns=0, x=-5.0, y=3.0), bytes.fromhex(runauth.new_key()))
    assert loop.on_message("goal", other_run, 0.0) == [] and loop.rejected_goals == 2
    ours = runauth.sign(Goal(stamp_ns=0, x=5.0, y=0.0), key)
    (topic, status), = loop.on_message("goal", ours, 0.0)
    assert status.state == "ready" and runauth.verify(status, key)   # the answer is signed
    assert not runauth.verify(PlannerStatus(stamp_ns=0, state="reached"), key)


# -- items 4, 7, 8 -------------------------------------------------------------------------------
def test_figures_freeze_at_a_nodes_death_and_keep_the_timeout():
    m = RunMonitor(timeout_s=60)
    for i in range(200):                    # the meter dies after 12 s; the sim runs on
        m.on_pose(pose(i * 0.1, i * 0.01))
        if i <= 120:
            m.on_battery(battery(i * 0.1, i * 0.01))
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
            m.on_pose(pose(t, t * 0.1))
            m.on_battery(battery(t, t))

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


# -- items 9, 10 ---------------------------------------------------------------------------------
@pytest.mark.parametrize("args,says", [
    (["--planner", "papff"], "did you mean 'papf'"),
    (["--planner", "PAPF"], "did you mean 'papf'"),
    (["--set", "unknown=1"], "unknown apf setting 'unknown'"),
    (["--set", "vmax=0.3"], "did you mean 'v_max'"),
    (["--set", "d_o=nan"], "d_o=nan: must be a finite number in [0.25, 25] m"),
    (["--seed", "-1"], "--seed=-1: must be an integer in [0, 4294967295]"),
    (["--params", "/bin/ls"], "is not a readable TOML file"),
    (["--params", "/nonexistent.toml"], "no such file"),
    (["--record", "/nonexistent/x.mcap"], "does not exist"),
    (["--timeout", "nan"], "--timeout=nan: must be a finite number"),
    (["--timeout", "inf"], "--timeout=inf"), (["--timeout", "0"], "--timeout=0"),
    (["--timeout", "-5"], "--timeout=-5"),
    (["--port", "-1"], "--port=-1: must be an integer in [1, 65535]"),
    (["--port", "70000"], "--port=70000"),
    (["--namespace", ""], "namespace"), (["--namespace", "*"], "namespace"),
    (["--namespace", "a//b"], "namespace"),
])
def test_bad_run_arguments_are_refused_before_anything_starts(args, says):
    p = papf("run", "--world", "open", "--json", *args)
    assert p.returncode == 2, (args, p.stdout, p.stderr)
    assert p.stdout == "" and says in p.stderr, (args, p.stderr)
    assert len(p.stderr.strip().splitlines()) == 1 and "Traceback" not in p.stderr


def test_a_port_held_by_another_listener_is_refused():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        port = s.getsockname()[1]
        p = papf("run", "--world", "open", "--port", port)
    assert p.returncode == 2 and "already listens" in p.stderr and p.stdout == ""


def test_plan_refuses_a_negative_seed_and_a_3d_world_is_refused_by_run():
    p = papf("plan", "--world", "open", "--seed", "-1")
    assert p.returncode == 2 and "--seed=-1" in p.stderr and "Traceback" not in p.stderr
    p = papf("run", "--world", "wang-3d-fig9", "--json")
    assert p.returncode == 2 and "is 3-D" in p.stderr and p.stdout == ""


def _world(goal, start=(0.0, 0.0), obstacles=()):
    return parse_world({"robot": {"start": list(start)}, "goal": {"position": list(goal)},
                        "obstacles": list(obstacles)})


def test_worlds_refuse_unreachable_goals_starts_in_obstacles_and_huge_coordinates():
    box = {"kind": "box", "center": [3.0, 0.0], "size": [1.0, 1.0]}
    with pytest.raises(WorldError, match=r"goal \(3, 0\) lies inside obstacles\[0\] \(box\)"):
        check_runnable(_world([3.0, 0.0], obstacles=[box]))
    with pytest.raises(WorldError, match=r"start \(3, 0\) is inside obstacles\[0\]"):
        check_runnable(_world([6.0, 0.0], start=(3.0, 0.0), obstacles=[box]))
    check_runnable(_world([3.0, 0.62], obstacles=[box]))     # beside it: fine
    with pytest.raises(WorldError, match="beyond the 1000 m"):
        _world([1e300, 0.0])
    many = [{"kind": "cylinder", "center": [i * 0.5 - 200.0, 50.0], "radius": 0.1}
            for i in range(2001)]
    check_runnable(_world([5.0, 0.0], obstacles=many))     # no obstacle limit any more
    for name in ("energy", "open", "papf-test-4", "wang-unreachable-goal", "wang-3d-fig9"):
        check_runnable(load_world(name))


def test_namespaces_must_make_valid_keys():
    for bad in ("", "*", "a//b", "/a", "a/", "a$b", "a?b", "a#b", "a b"):
        with pytest.raises(ValueError):
            Keys(bad)
    assert Keys("lab/r1").scan == "lab/r1/scan"


def test_check_errors_are_config_errors():
    from papf.launch.preflight import planner_name

    with pytest.raises(ConfigError, match="did you mean 'arapf'"):
        planner_name("ARAPF")


def test_a_launched_sessions_key_is_readable_by_its_user_only(tmp_path, monkeypatch):
    """`papf goal` on the same host signs with the session's key; nobody else gets it."""
    import os
    import stat

    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    key = runauth.new_key()
    path = runauth.publish_key("lab/r1", key)
    assert stat.S_IMODE(os.stat(path).st_mode) == 0o600
    assert stat.S_IMODE(os.stat(path.parent).st_mode) == 0o700
    assert runauth.read_key("lab/r1") == bytes.fromhex(key)
    m = RunMonitor(timeout_s=100, goal=(5.0, 0.0, 0.1))
    m.on_goal(runauth.sign(Goal(stamp_ns=0, x=1.5, y=1.0), bytes.fromhex(key)))
    assert m.goal == (1.5, 1.0, 0.1)
    runauth.withdraw_key("lab/r1", key)
    assert runauth.read_key("lab/r1") is None
