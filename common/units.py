"""Time on the wire is integer nanoseconds; these are the only conversions.

A stamp is valid when it lies in ``[0, MAX_STAMP_NS]``: a sim clock starts at 0 and
a wall clock is nanoseconds since the epoch, both far below 2**62 (146 years).
"""

from __future__ import annotations

NS_PER_S = 1_000_000_000       # [ns/s]
MAX_STAMP_NS = 2**62           # [ns] largest stamp any node accepts (see module doc)


def s_to_ns(seconds: float) -> int:
    """Seconds -> integer nanoseconds, rounded to the nearest."""
    return int(round(seconds * NS_PER_S))


def ns_to_s(ns: int) -> float:
    """Integer nanoseconds -> seconds."""
    return ns / NS_PER_S


def stamp_ok(stamp_ns: int) -> bool:
    """A stamp a node may act on: an integer in ``[0, MAX_STAMP_NS]``."""
    return isinstance(stamp_ns, int) and 0 <= stamp_ns <= MAX_STAMP_NS
