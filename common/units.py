"""Time on the wire is integer nanoseconds; these are the only conversions.

A stamp is valid when it lies in ``[0, MAX_STAMP_NS]``: a sim clock starts at 0 and
a wall clock is nanoseconds since the epoch, both far below 2**62 (146 years).
:class:`StampGuard` applies that to received messages, and drops stamps that go back
on a topic whose stamps only go forward.
"""

from __future__ import annotations

NS_PER_S = 1_000_000_000       # [ns/s]
MAX_STAMP_NS = 2**62           # [ns] largest stamp any node accepts (see module doc)
# [s] wall time a lockstep scan waits for its partners (odometry, pose, objects) in the
# planner and the tracker. Longer than the driver's lockstep timeout (2 s): on a slow or
# overloaded machine a late partner is waited for, so an answer never depends on the
# machine's speed (with 0.25 s, a run at load 30 answered a scan with the odometry 40 ms
# older); a lost partner shows first as the driver's `node_fault` in the run's figures,
# and the fallback after this timeout then keeps the node answering.
LOCKSTEP_PAIR_TIMEOUT_S = 3.0


def s_to_ns(seconds: float) -> int:
    """Seconds -> integer nanoseconds, rounded to the nearest."""
    return int(round(seconds * NS_PER_S))


def ns_to_s(ns: int) -> float:
    """Integer nanoseconds -> seconds."""
    return ns / NS_PER_S


def stamp_ok(stamp_ns: int) -> bool:
    """A stamp a node may act on: an integer in ``[0, MAX_STAMP_NS]``."""
    return isinstance(stamp_ns, int) and not isinstance(stamp_ns, bool) and (
        0 <= stamp_ns <= MAX_STAMP_NS)


class StampGuard:
    """Decide whether a received message's stamp may be acted on.

    :meth:`check` returns ``""`` for a good stamp, else why it is bad: outside
    ``[0, MAX_STAMP_NS]``, or — on the ``ordered`` topics — older than the last good one.
    A stamp of 0 is in order for a node that serves run after run (sim time restarts at 0
    with each run); ``restart_at_zero=False`` for a watcher of one run (the launcher).
    """

    def __init__(self, ordered: frozenset[str] | set[str] = frozenset(),
                 restart_at_zero: bool = True):
        self.ordered = ordered
        self.restart_at_zero = restart_at_zero
        self.last: dict[str, int] = {}

    def check(self, topic: str, msg) -> str:
        """What is wrong with ``msg`` on ``topic`` (stamp out of range or back); "" if nothing."""
        stamp = getattr(msg, "stamp_ns", 0)
        if not stamp_ok(stamp):
            return f"stamp {stamp!r} ns is outside [0, {MAX_STAMP_NS}]"
        if topic in self.ordered:
            last = self.last.get(topic, 0)
            if stamp < last and (stamp > 0 or not self.restart_at_zero):
                return f"stamp {stamp} ns is older than the last one on this topic ({last} ns)"
            self.last[topic] = stamp
        return ""
