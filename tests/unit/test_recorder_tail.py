"""The recorder's end of run: run_ended may overtake the samples of its own instant."""

from nodes.recorder.tail import RunEndWatch, stamp_of
from schemas.messages import Event, Goal, Odometry

S = 1_000_000_000


def odom(t):
    return Odometry(stamp_ns=t, x=0.0, y=0.0, yaw=0.0, v=0.0, w=0.0).to_bytes()


def ended(t):
    return Event(stamp_ns=t, kind="run_ended", source="launcher", detail="{}").to_bytes()


def test_the_tail_waits_for_every_live_key_to_reach_the_end_stamp():
    w = RunEndWatch("ns/events")
    w.arrived("ns/goal", Goal(stamp_ns=0, x=1.0, y=0.0).to_bytes(), 0)       # long ago: not live
    w.arrived("ns/odom", odom(9 * S), 100 * S)
    w.arrived("ns/scan", odom(9 * S), 100 * S)                                # (any stamped message)
    w.arrived("ns/events", ended(10 * S), 100 * S + 1)
    assert w.seen and not w.complete and w.waiting == {"ns/odom", "ns/scan"}
    w.arrived("ns/odom", odom(10 * S), 100 * S + 2)
    w.arrived("ns/scan", odom(10 * S - 1), 100 * S + 3)                       # still before T
    assert w.waiting == {"ns/scan"} and not w.complete
    w.arrived("ns/scan", odom(10 * S), 100 * S + 4)                           # the late scan of T
    assert w.complete


def test_a_payload_without_our_stamp_does_not_hold_the_file_open():
    w = RunEndWatch("ns/events")
    w.arrived("ns/cdr", b"\x00\x01\x00\x00garbage", 5)
    w.arrived("ns/events", ended(3), 6)
    assert w.complete and stamp_of(b"\x00\x01") is None and stamp_of(odom(42)) == 42


def test_other_events_and_bad_events_end_nothing():
    w = RunEndWatch("ns/events")
    w.arrived("ns/events", b"\xc1not msgpack", 1)
    w.arrived("ns/events", Event(stamp_ns=1, kind="node_fault", source="x", detail="").to_bytes(), 2)
    assert not w.seen and not w.complete


def test_a_key_that_already_reached_the_end_stamp_is_not_waited_for():
    w = RunEndWatch("ns/events")
    w.arrived("ns/scan", odom(10 * S), 100 * S)          # the scan of T came first
    w.arrived("ns/odom", odom(9 * S), 100 * S)
    w.arrived("ns/events", ended(10 * S), 100 * S + 1)
    assert w.waiting == {"ns/odom"}
