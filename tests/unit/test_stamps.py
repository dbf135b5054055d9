"""Stamp windows (common/units.py ``StampGuard``): backwards stamps on ordered topics, stamps from
the future, samples a little ahead outvoted by the real stream."""

from __future__ import annotations

from common.units import MAX_STAMP_NS, StampGuard
from schemas.keys import STAMP_ORDERED
from schemas.messages import Goal
from tests.support.messages import odom as _odom


def test_backwards_stamp_is_dropped_on_ordered_topics_only():
    g = StampGuard(STAMP_ORDERED)
    assert [g.check("odom", _odom(t)) == "" for t in (100, 200, 150, 200, 300)] == [
        True, True, False, True, True]
    assert g.check("odom", _odom(0)) == ""            # a new run restarts sim time at 0
    assert g.check("odom", _odom(20)) == ""
    assert g.check("goal", Goal(stamp_ns=5, x=0, y=0)) == ""
    assert g.check("goal", Goal(stamp_ns=1, x=0, y=0)) == ""   # not an ordered topic


def test_a_stamp_from_the_future_is_dropped_and_moves_nothing():
    wall = [0]
    guard = StampGuard({"scan"}, wall=lambda: wall[0])
    assert guard.check("scan", _odom(100_000_000)) == ""
    assert "future" in guard.check("scan", _odom(MAX_STAMP_NS))
    wall[0] = 10_000_000   # 10 ms later: the real stream goes on
    assert guard.check("scan", _odom(200_000_000)) == ""


def test_samples_a_little_ahead_are_outvoted_by_the_real_stream():
    guard = StampGuard({"scan"}, wall=lambda: 0)
    assert guard.check("scan", _odom(1_000_000_000)) == ""
    assert guard.check("scan", _odom(1_550_000_000)) == ""          # spoofed, 0.55 s ahead
    real = [guard.check("scan", _odom(1_100_000_000 + i * 100_000_000)) for i in range(6)]
    assert all("older" in why for why in real[:4])                   # dropped a while...
    assert real[4:] == ["", ""] and guard.resyncs == 1                # ...then the stream wins
