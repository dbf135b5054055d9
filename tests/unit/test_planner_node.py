"""Planner process logic: lockstep pairing and staleness (pure), the node's help and usage errors."""

import json
import logging
import subprocess
import sys

from hypothesis import given, settings
from hypothesis import strategies as st

from common import runauth
from common.transport import Node
from nodes.planner.loop import PlannerLoop
from nodes.planner.params import answer, current
from nodes.planner.registry import make_planner
from nodes.planner.road import Lanes
from schemas import Keys, PlannerStatus
from schemas.messages import (
    Goal,
    Objects,
    ObjectTrack,
)
from tests.support.messages import odom, scan
from tests.support.messages import odom as _odom
from tests.support.messages import scan_63 as _scan

MS = 1_000_000


KEY = bytes.fromhex(runauth.new_key())


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


def test_lockstep_a_late_partner_is_logged_with_how_long_the_scan_waited():
    seen = []

    class Log:   # what the loop logs, as the lines it would write
        def warning(self, fmt, *args):
            seen.append(fmt % args)

    lp = loop(log=Log())
    lp.on_message("scan", scan(100 * MS), 0.0)
    assert lp.on_message("odom", odom(100 * MS), 0.5)[0][1].stamp_ns == 100 * MS
    assert seen == []                                              # in time: nothing said
    lp.on_message("scan", scan(200 * MS), 1.0)
    assert lp.on_message("odom", odom(200 * MS), 3.5)[0][1].stamp_ns == 200 * MS
    assert seen == ["scan 200000000 waited 2.50 s for its odometry/objects"]


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


def _ask(planner, request: dict, check) -> dict:
    return answer("papf", planner, json.dumps(request).encode(), check)[0]


def test_a_keyed_planner_lists_to_anyone_but_changes_only_for_its_key():
    planner = make_planner("papf")
    check = runauth.RequestCheck(KEY)
    before = current("papf", planner)
    assert _ask(planner, {}, check)["params"] == before            # reading is open
    reply = _ask(planner, {"set": ["apf.d_o=0.6"]}, check)          # unsigned
    assert "not signed" in reply["error"] and current("papf", planner) == before
    other = runauth.sign_request({"set": ["apf.d_o=0.6"]}, bytes(16))
    assert "not signed" in _ask(planner, other, check)["error"]
    signed = runauth.sign_request({"set": ["apf.d_o=0.6"]}, KEY)
    assert _ask(planner, signed, check)["error"] == ""
    assert current("papf", planner)["apf.d_o"] == 0.6
    assert "not signed" in _ask(planner, signed, check)["error"]    # a replay: nonce seen
    low = runauth.sign_request({"set": ["apf.d_o=1e-9"]}, KEY)      # signed, still checked
    assert "must be" in _ask(planner, low, check)["error"]
    assert current("papf", planner)["apf.d_o"] == 0.6


@settings(max_examples=60, deadline=None)
@given(st.binary(max_size=300))
def test_garbage_queries_change_nothing(payload):
    planner = make_planner("apf")
    before = current("apf", planner)
    reply, changed = answer("apf", planner, payload, runauth.RequestCheck(KEY))
    assert changed == [] and current("apf", planner) == before and "params" in reply


def test_planner_ignores_an_extreme_stamp_pair():
    """The reproduction: odom + scan at 2**64-1 made the planner stagnate at once."""
    node = Node("planner", None, Keys("t"), logging.getLogger("p"))
    loop = PlannerLoop(make_planner("apf"))
    out = loop.on_message("goal", Goal(stamp_ns=0, x=5.0, y=0.0), 0.0)
    for t in (0, 100_000_000):
        for topic, msg in (("odom", _odom(t)), ("scan", _scan(t))):
            out += loop.on_message(topic, node.accept(topic, msg.to_bytes()), 0.0)
    for stamp in (2**64 - 1, -2**63):
        for topic, msg in (("odom", _odom(stamp)), ("scan", _scan(stamp))):
            got = node.accept(topic, msg.to_bytes())
            assert got is None
    statuses = [m.state for t, m in out if t == "planner/status"]
    assert statuses == ["ready", "driving", "driving"]
    assert sum(node.bad_messages.values()) == 4


def test_planner_state_neither_built_nor_returned_when_nobody_listens():
    """want_state false: the same commands and statuses, no planner/state (debug) at all."""
    def run(want: bool) -> list:
        loop = PlannerLoop(make_planner("apf"), want_state=lambda: want)
        out = loop.on_message("goal", Goal(stamp_ns=0, x=5.0, y=0.0), 0.0)
        for t in (0, 100_000_000, 200_000_000):
            out += loop.on_message("odom", _odom(t), 0.0) + loop.on_message("scan", _scan(t), 0.0)
        out += loop.on_message("scan", _scan(900_000_000), 0.0) + loop.poll(10.0)  # stale
        out += loop.on_message("goal", Goal(stamp_ns=0, x=0.05, y=0.0), 0.0)  # within reach
        t = 1_000_000_000
        return out + loop.on_message("odom", _odom(t), 0.0) + loop.on_message("scan", _scan(t), 0.0)

    full, lean = run(True), run(False)
    assert [t for t, _ in full].count("planner/state") == 5
    assert [m.state for t, m in lean if t == "planner/status"][-1] == "reached"
    assert any(m.mode == "stale" for t, m in full if t == "planner/state")
    assert [(t, m) for t, m in full if t != "planner/state"] == lean


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


class _Subscriptions:
    """What a planner's robot subscribes to, and how (a stand-in for its Node)."""

    keys = Keys("rosbot")

    def __init__(self):
        self.calls = {}
        self.session = self

    def share(self, name, log=None):
        return self

    def subscribe(self, topic, msg_type=None, *, handler=None, batched=False):
        self.calls[topic] = "batched" if batched else "inbox"

    def declare_publishers(self, *topics, on_demand=()):
        pass

    def declare_queryable(self, key, handler):
        return self

    def listened(self, topic):
        return False


def test_nothing_a_lockstep_cycle_waits_for_is_batched():
    """A scan's odometry and tracks come into the inbox as the scan does: batched in Zenoh's
    channel, one now and then reached the loop only with the next scan (docs/architecture.md,
    "Lockstep")."""
    from nodes.planner.__main__ import Served, parse_args

    args = parse_args(["--planner", "apf", "--objects"])
    node = _Subscriptions()
    Served(node, "", make_planner("apf"), args, logging.getLogger("test"))
    assert node.calls == {"scan": "inbox", "goal": "inbox", "odom": "inbox", "objects": "inbox"}
