"""Message rates as ``ros2 topic hz`` reports them (pure; times are passed in).

Two rates per key: by arrival (wall clock, what the network delivers) and by the
messages' own stamps (``stamp_ns``; in a lockstep simulation this is the *sim-time*
rate, 10 Hz for scans however fast the run goes, while the wall rate follows the CPU).
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

from common.units import NS_PER_S

DEFAULT_WINDOW = 1000   # [messages] kept for the statistics (ros2 topic hz keeps 10000)


@dataclass(frozen=True)
class Rate:
    hz: float            # [Hz] mean arrival rate over the window (nan: < 2 messages)
    min_s: float         # [s] shortest gap between arrivals
    max_s: float         # [s] longest gap
    sd_s: float          # [s] standard deviation of the gaps
    window: int          # messages in the window
    stamp_hz: float      # [Hz] rate by the messages' own stamps (nan: no stamps)

    def line(self, key: str) -> str:
        """One line of ``papf topic hz`` for ``key``: rate [Hz], gaps [s], window."""
        if math.isnan(self.hz):
            return f"{key}: waiting for messages ({self.window} so far)"
        stamps = "" if math.isnan(self.stamp_hz) else f"; by stamps {self.stamp_hz:.3f} Hz"
        return (f"{key}: {self.hz:.3f} Hz (gaps min {self.min_s:.4f} s, max {self.max_s:.4f} s, "
                f"sd {self.sd_s:.4f} s; window {self.window}){stamps}")


class HzStats:
    """``add(arrival_s, stamp_ns)`` per message; :meth:`rate` over the last ``window``."""

    def __init__(self, window: int = DEFAULT_WINDOW):
        if window < 2:
            raise ValueError(f"window {window} must be >= 2 messages")
        self.arrivals: deque[float] = deque(maxlen=window)
        self.stamps: deque[int] = deque(maxlen=window)
        self.count = 0

    def add(self, arrival_s: float, stamp_ns: int | None = None) -> None:
        """Note a message that arrived at ``arrival_s`` [s], stamped ``stamp_ns`` [ns]."""
        self.count += 1
        self.arrivals.append(arrival_s)
        if stamp_ns is not None:
            self.stamps.append(stamp_ns)

    def rate(self) -> Rate:
        """The rate [Hz] and gap statistics [s] over the window (NaN below two messages)."""
        n = len(self.arrivals)
        if n < 2:
            return Rate(math.nan, math.nan, math.nan, math.nan, n, math.nan)
        t = list(self.arrivals)
        gaps = [b - a for a, b in zip(t, t[1:], strict=False)]
        mean = (t[-1] - t[0]) / (n - 1)
        sd = math.sqrt(sum((g - mean) ** 2 for g in gaps) / len(gaps))
        return Rate(1.0 / mean if mean > 0 else math.inf, min(gaps), max(gaps), sd, n,
                    stamp_rate(list(self.stamps)))


def stamp_rate(stamps: list[int]) -> float:
    """(n - 1) / (newest - oldest stamp) [Hz] over the newest run of non-decreasing stamps
    (a new run restarts its clock at 0); nan if fewer than two or no time passed."""
    i = len(stamps) - 1
    while i > 0 and stamps[i - 1] <= stamps[i]:
        i -= 1
    tail = stamps[max(i, 0):]
    if len(tail) < 2 or tail[-1] <= tail[0]:
        return math.nan
    return (len(tail) - 1) * NS_PER_S / (tail[-1] - tail[0])
