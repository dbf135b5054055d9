"""What the emulated link did: bytes, chunks, the delays it applied, its outages.

Delays are kept in a bounded reservoir per direction (Vitter's algorithm R: every chunk
has the same chance to be in it), so a day-long link costs the same memory as a minute.
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass, field

RESERVOIR = 50_000   # delay samples kept per direction


def percentile(sorted_values: list[float], p: float) -> float | None:
    """The ``p``-th percentile (0-100) of ascending ``sorted_values``, linear between ranks;
    None for no values."""
    if not sorted_values:
        return None
    k = (len(sorted_values) - 1) * p / 100.0
    lo, hi = math.floor(k), math.ceil(k)
    return sorted_values[lo] + (sorted_values[hi] - sorted_values[lo]) * (k - lo)


@dataclass
class DirectionStats:
    """One direction's counters and applied delays [s]."""

    bytes: int = 0
    chunks: int = 0
    dropped: int = 0          # chunks dropped by a reset-mode outage
    lost: int = 0             # chunks that waited a retransmission timeout (loss)
    max_queued_bytes: int = 0
    delays: list[float] = field(default_factory=list)
    seen: int = 0
    _rng: random.Random = field(default_factory=lambda: random.Random(0))

    def add(self, size: int, delay_s: float) -> None:
        """A chunk of ``size`` bytes delivered ``delay_s`` after it reached the link."""
        self.bytes += size
        self.chunks += 1
        self.seen += 1
        if len(self.delays) < RESERVOIR:
            self.delays.append(delay_s)
        else:
            j = self._rng.randrange(self.seen)
            if j < RESERVOIR:
                self.delays[j] = delay_s

    def to_json(self) -> dict:
        s = sorted(self.delays)

        def ms(v: float | None) -> float | None:
            return None if v is None else round(v * 1000.0, 3)
        return {"bytes": self.bytes, "chunks": self.chunks, "dropped": self.dropped,
                "lost": self.lost, "max_queued_bytes": self.max_queued_bytes,
                "delay_ms": {"p50": ms(percentile(s, 50)), "p90": ms(percentile(s, 90)),
                             "p99": ms(percentile(s, 99)), "max": ms(s[-1] if s else None),
                             "mean": ms(sum(s) / len(s) if s else None)}}


@dataclass
class LinkStats:
    """The whole link's figures (``papf link --stats FILE``, ``papf run --link``'s JSON)."""

    directions: dict[str, DirectionStats] = field(
        default_factory=lambda: {"out": DirectionStats(), "back": DirectionStats()})
    connections: int = 0          # accepted from the listening side
    connect_failures: int = 0     # the --to side did not answer
    resets: int = 0               # connections reset by reset-mode outages
    refused: int = 0              # connections refused during reset-mode outages

    def summary(self) -> str:
        """One line per direction, for stderr at exit."""
        lines = []
        for name, d in self.directions.items():
            j = d.to_json()["delay_ms"]
            lines.append(f"{name}: {d.bytes:,} bytes in {d.chunks:,} chunks, delay p50 "
                         f"{_num(j['p50'])} / p99 {_num(j['p99'])} / max {_num(j['max'])} ms"
                         + (f", {d.dropped} dropped" if d.dropped else "")
                         + (f", {d.lost} resent" if d.lost else ""))
        return "; ".join(lines)

    def to_json(self) -> dict:
        return {"connections": self.connections, "connect_failures": self.connect_failures,
                "resets": self.resets, "refused": self.refused,
                "directions": {k: d.to_json() for k, d in self.directions.items()}}


def _num(v: float | None) -> str:
    return "-" if v is None else f"{v:.1f}"
