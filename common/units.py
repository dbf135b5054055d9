"""Time on the wire is integer nanoseconds; these are the only conversions, and the one
rate-to-period rule of the sim's time grid (:func:`period_ns`: the world simulator's
odometry and scan instants, the simulated LiDAR's scans).

A stamp is valid when it lies in ``[0, MAX_STAMP_NS]``: a sim clock starts at 0 and
a wall clock is nanoseconds since the epoch, both far below 2**62 (146 years).
:class:`StampGuard` applies that to received messages, and drops stamps that go back
on a topic whose stamps only go forward.
"""

from __future__ import annotations

import time

from common.errors import ConfigError

NS_PER_S = 1_000_000_000       # [ns/s]
MAX_STAMP_NS = 2**62           # [ns] largest stamp any node accepts (see module doc)
LOCKSTEP_TIMEOUT_S = 2.0       # [s wall] the simulator's wait for a scan's command (default)
# [s] wall time a lockstep scan waits for its partners (odometry, pose, objects) in the
# planner and the tracker. Longer than the driver's lockstep timeout (2 s): on a slow or
# overloaded machine a late partner is waited for, so an answer never depends on the
# machine's speed (with 0.25 s, a run at load 30 answered a scan with the odometry 40 ms
# older); a lost partner shows first as the driver's `node_fault` in the run's figures,
# and the fallback after this timeout then keeps the node answering.
LOCKSTEP_PAIR_TIMEOUT_S = 3.0


def pair_timeout_s(lockstep_timeout_s: float) -> float:
    """The planner's and tracker's pair timeout [s] beside a driver's lockstep timeout: the
    default (:data:`LOCKSTEP_PAIR_TIMEOUT_S`), or a second longer than a longer timeout."""
    return max(LOCKSTEP_PAIR_TIMEOUT_S, lockstep_timeout_s + 1.0)


def s_to_ns(seconds: float) -> int:
    """Seconds -> integer nanoseconds, rounded to the nearest."""
    return int(round(seconds * NS_PER_S))


def ns_to_s(ns: int) -> float:
    """Integer nanoseconds -> seconds."""
    return ns / NS_PER_S


def period_ns(hz: float, what: str) -> int:
    """An exact integer period [ns] for a rate [Hz]; ConfigError if 1 s is not a whole number
    of ns periods (every instant of the time grid is then exact: docs/architecture.md "Time")."""
    if not (hz > 0) or hz != hz:
        raise ConfigError(f"{what} = {hz!r} Hz must be > 0")
    period = round(NS_PER_S / hz)
    if period * hz != NS_PER_S:
        raise ConfigError(f"{what} = {hz} Hz gives a period of {NS_PER_S / hz} ns, not an integer; "
                          "use a rate that divides 1e9 ns (e.g. 10, 20, 25, 50 Hz)")
    return period


def stamp_ok(stamp_ns: int) -> bool:
    """A stamp a node may act on: an integer in ``[0, MAX_STAMP_NS]``."""
    return isinstance(stamp_ns, int) and not isinstance(stamp_ns, bool) and (
        0 <= stamp_ns <= MAX_STAMP_NS)


AHEAD_SLACK_NS = 2 * NS_PER_S   # [ns] a stamp may lead the receiver's clock by this much
SIM_RATE_MAX = 1000             # [-] sim seconds a lockstep run may pass per wall second, at most
RESYNC_AFTER = 5                # [-] samples in order among themselves that outvote one ahead


class StampGuard:
    """Decide whether a received message's stamp may be acted on.

    :meth:`check` returns ``""`` for a good stamp, else why it is bad: outside
    ``[0, MAX_STAMP_NS]``, or — on the ``ordered`` topics — older than the last good one, or
    further ahead of the receiver's own clock than time can have passed.
    A stamp of 0 is in order for a node that serves run after run (sim time restarts at 0
    with each run); ``restart_at_zero=False`` for a watcher of one run (the launcher).

    The receiver's clock window (issue 31: one scan stamped 2^62 ns, or spoofed scans a
    little ahead, must not blind a node): after the last good stamp ``s`` received at wall
    time ``w``, a stamp is "from the future" when it lies beyond ``s + AHEAD_SLACK_NS +
    SIM_RATE_MAX * (now - w)`` (sim time never runs faster than that against the wall, in
    lockstep or real time); it is dropped and moves nothing. And a stamp that got through but
    is ahead of the stream — every later sample older than it — is outvoted: after
    :data:`RESYNC_AFTER` samples in order among themselves but behind it, the guard takes
    them as the stream's clock again (counted in :attr:`resyncs`). Sealed streams
    (:mod:`common.seal`) keep keyless peers out altogether; this is the guard for what
    is left (nodes run alone, a faulty node).
    """

    def __init__(self, ordered: frozenset[str] | set[str] = frozenset(),
                 restart_at_zero: bool = True, wall=None):
        self.ordered = ordered
        self.restart_at_zero = restart_at_zero
        self.wall = wall or time.monotonic_ns
        self.last: dict[str, int] = {}
        self._seen_at: dict[str, int] = {}          # wall ns the last good stamp came
        self._behind: dict[str, list[int]] = {}     # stamps behind `last`, in order, recent
        self.resyncs = 0

    def check(self, topic: str, msg) -> str:
        """What is wrong with ``msg`` on ``topic`` (stamp out of range, back, or ahead); ""
        if nothing."""
        stamp = getattr(msg, "stamp_ns", 0)
        if not stamp_ok(stamp):
            return f"stamp {stamp!r} ns is outside [0, {MAX_STAMP_NS}]"
        if topic not in self.ordered:
            return ""
        now = self.wall()
        last = self.last.get(topic)
        if last is not None:
            horizon = last + AHEAD_SLACK_NS + SIM_RATE_MAX * max(0, now - self._seen_at[topic])
            if stamp > horizon:
                return (f"stamp {stamp} ns is ahead of this node's clock (at most {horizon} ns "
                        "now): from the future")
            if stamp < last and (stamp > 0 or not self.restart_at_zero):
                if not self._outvoted(topic, stamp):
                    return f"stamp {stamp} ns is older than the last one on this topic ({last} ns)"
        self.last[topic], self._seen_at[topic] = stamp, now
        self._behind.pop(topic, None)
        return ""

    def _outvoted(self, topic: str, stamp: int) -> bool:
        """True when ``stamp`` and the samples behind ``last`` before it are in order and
        enough: the stream goes on from them (``last`` was a stamp from the future)."""
        behind = self._behind.setdefault(topic, [])
        if behind and stamp <= behind[-1]:
            behind.clear()
        behind.append(stamp)
        if len(behind) < RESYNC_AFTER:
            return False
        self.resyncs += 1
        return True
