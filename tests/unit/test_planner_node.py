"""Planner process logic: lockstep pairing and staleness (pure), the node's help and usage errors."""

import subprocess
import sys

from nodes.planner.loop import PlannerLoop
from nodes.planner.registry import make_planner
from nodes.planner.road import Lanes
from schemas.messages import (
    Goal,
    Objects,
    ObjectTrack,
)
from tests.support.messages import odom, scan

MS = 1_000_000


def loop(**kw):
    lp = PlannerLoop(make_planner("apf"), **kw)
    out = lp.on_message("goal", Goal(stamp_ns=7, x=3.0, y=0.0), 0.0)
    assert [(t, m.state, m.stamp_ns) for t, m in out] == [("planner/status", "ready", 7)]
    return lp


def test_lockstep_pairs_same_stamp_in_either_order():
    lp = loop()
    assert lp.on_message("scan", scan(100 * MS), 0.0) == []          # waits for odom(100 ms)
    assert lp.on_message("odom", odom(80 * MS), 0.0) == []
    out = lp.on_message("odom", odom(100 * MS, x=0.5), 0.01)
    assert [t for t, _ in out] == ["cmd_vel", "planner/state", "planner/status"]
    assert out[0][1].stamp_ns == 100 * MS and out[0][1].v > 0
    assert lp.on_message("odom", odom(200 * MS), 0.02) == []
    out = lp.on_message("scan", scan(200 * MS), 0.03)                 # odom first this time
    assert out[0][1].stamp_ns == 200 * MS and out[2][1].state == "driving"


def test_lockstep_missing_odom_falls_back_after_pair_timeout():
    lp = loop(pair_timeout_s=0.25, stale_timeout_s=0.5)
    lp.on_message("odom", odom(80 * MS), 0.0)
    lp.on_message("scan", scan(100 * MS), 0.0)
    assert lp.poll(0.1) == []
    out = lp.poll(0.3)
    assert out[0][1].stamp_ns == 100 * MS and out[0][1].v > 0         # fresh older odom used
    lp.on_message("scan", scan(900 * MS), 0.4)
    out = lp.poll(0.7)                                                # newest odom is 820 ms old
    assert (out[0][1].v, out[0][1].w) == (0.0, 0.0) and "stale" in out[2][1].reason


class Seen:
    """Records what the planner shows a strategy through ``observe``: (road, track x, t [ns])."""

    def __init__(self, planner):
        self.calls = []
        planner.strategy.observe = lambda objects, road, t, v: self.calls.append(
            (road, tuple(o.x for o in objects), round(t * 1e9)))


def objects(t):
    """Tracks of instant t: one object at x = 1 + t [s] (so each instant's is recognisable)."""
    return Objects(stamp_ns=t, source="truth", tracks=(ObjectTrack(id=1, x=1.0 + t / 1e9, y=0.0),))


def test_lockstep_with_objects_waits_for_the_scans_own_tracks():
    lp = PlannerLoop(make_planner("apf"), objects=True)
    seen = Seen(lp.planner)
    lp.on_message("goal", Goal(stamp_ns=7, x=3.0, y=0.0, road_lanes=2, road_y_min=-0.3,
                               road_lane_width=0.6), 0.0)
    assert lp.on_message("objects", objects(0), 0.0) == []
    assert lp.on_message("scan", scan(100 * MS), 0.0) == []
    assert lp.on_message("odom", odom(100 * MS), 0.0) == []          # objects(100 ms) missing
    out = lp.on_message("objects", objects(100 * MS), 0.0)
    assert out[0][1].stamp_ns == 100 * MS
    assert seen.calls == [(Lanes(-0.3, 0.6, 2), (1.1,), 100 * MS)]


def test_lockstep_objects_fall_back_to_the_newest_older_after_pair_timeout():
    lp = loop(objects=True, pair_timeout_s=0.25)
    seen = Seen(lp.planner)
    lp.on_message("objects", objects(0), 0.0)
    lp.on_message("odom", odom(100 * MS), 0.0)
    assert lp.on_message("scan", scan(100 * MS), 0.0) == []
    assert lp.poll(0.3)[0][1].stamp_ns == 100 * MS
    assert seen.calls == [(None, (1.0,), 100 * MS)]                    # objects(0); no road


def test_without_objects_the_loop_ignores_them():
    lp = loop()
    seen = Seen(lp.planner)
    lp.on_message("objects", objects(100 * MS), 0.0)
    lp.on_message("odom", odom(100 * MS), 0.0)
    assert lp.on_message("scan", scan(100 * MS), 0.0)[0][1].stamp_ns == 100 * MS
    assert seen.calls == [(None, (), 100 * MS)]


def test_realtime_uses_latest_odom_and_stops_when_stale():
    lp = loop(realtime=True, stale_timeout_s=0.5)
    lp.on_message("odom", odom(100 * MS), 0.0)
    out = lp.on_message("scan", scan(400 * MS), 0.0)
    assert out[0][1].v > 0
    out = lp.on_message("scan", scan(700 * MS), 0.1)                  # odom 600 ms old
    assert (out[0][1].v, out[0][1].w) == (0.0, 0.0)
    assert lp.poll(0.3) == []                                         # scans are fresh
    out = lp.poll(0.7)                                                # no scan for 0.6 s wall
    assert [t for t, _ in out] == ["cmd_vel"] and out[0][1].v == 0.0
    assert lp.poll(0.75) == [] and len(lp.poll(0.81)) == 1            # repeated every 0.1 s


def test_help_lists_every_planner():
    r = subprocess.run([sys.executable, "-m", "nodes.planner", "--help"], capture_output=True,
                       text=True, timeout=60, start_new_session=True)
    assert r.returncode == 0 and "{apf,arapf,iapf,orca,papf,social_force,wang,wang-apf}" in r.stdout


def test_bad_setting_exits_2():
    r = subprocess.run([sys.executable, "-m", "nodes.planner", "--set", "d_o=far"],
                       capture_output=True, text=True, timeout=60, start_new_session=True)
    assert r.returncode == 2 and "d_o" in r.stderr


def test_lockstep_pair_timeout_outlasts_the_drivers_lockstep_timeout():
    """A slow machine must not change an answer: the planner and the tracker wait for a
    scan's partners longer than the driver waits for the planner's command, in the node
    defaults and in the `sim` profile papf run starts."""
    from pathlib import Path

    from common.optional import tomllib
    from common.units import LOCKSTEP_PAIR_TIMEOUT_S
    from nodes.tracker.core import Tracker, TrackerParams
    from nodes.tracker.loop import TrackerLoop
    from nodes.world_sim.__main__ import build_parser

    driver_default = build_parser().parse_args([]).lockstep_timeout
    profile = tomllib.loads((Path(__file__).resolve().parents[2] / "papf" / "launch" / "profiles" / "sim.toml").read_text())
    assert LOCKSTEP_PAIR_TIMEOUT_S > max(driver_default, float(profile["defaults"]["lockstep_timeout"]))
    assert loop().pair_timeout_s == LOCKSTEP_PAIR_TIMEOUT_S
    assert TrackerLoop(Tracker(TrackerParams())).pair_timeout_s == LOCKSTEP_PAIR_TIMEOUT_S
