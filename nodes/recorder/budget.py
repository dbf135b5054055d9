"""The recorder's bounds per key (pure; no Zenoh): a flood on one key never starves the others.

Every sample is admitted or dropped on Zenoh's receiving thread by :meth:`Budget.admit`, which
costs a few dictionary look-ups (no decoding, no copy of a dropped payload):

- a **rate and byte budget per key** (token buckets over wall time): at most
  :data:`RATE_HZ` samples and :data:`BYTES_PER_S` bytes a second per key, with bursts of
  :data:`BURST_S` seconds' worth. The stack's busiest keys stay far below (odometry 50 Hz of
  sim time, ~1,000 a second in a fast lockstep run; a planner state of tens of KB at 10 Hz);
- a **bound on what waits to be written**: at most :data:`QUEUED_BYTES_MAX` bytes queued for
  the writer in all. Past half of it, a key holding more than its fair share of the queue
  (the bound over the keys that have something queued) has its new samples dropped, so the
  small real streams still get in while a flood waits its turn.

Every drop is counted per key and reason (:attr:`Budget.dropped`); the recording's summary
and ``papf info`` name them.
"""

from __future__ import annotations

import time
from collections import Counter

RATE_HZ = 20_000                 # [1/s] samples per key (lockstep odometry: ~1,000/s; the
                                 # recorder writes ~10,000 small samples/s: papf bench recorder)
BYTES_PER_S = 16 * 1024 * 1024   # [B/s] per key
BURST_S = 2.0                    # [s] of budget a quiet key saves up
QUEUED_BYTES_MAX = 64 * 1024 * 1024   # [B] waiting for the writer, all keys together
OVER_RATE, OVER_BYTES, QUEUE_FULL = "rate", "bytes", "queue"


class _Bucket:
    __slots__ = ("samples", "bytes", "t")

    def __init__(self, now: float, samples: float = RATE_HZ * BURST_S,
                 nbytes: float = BYTES_PER_S * BURST_S):
        self.samples, self.bytes, self.t = samples, nbytes, now


class Budget:
    """Admission of samples per key (module doc): :meth:`admit` runs on Zenoh's thread,
    :meth:`written` on the writer's (the interpreter's lock keeps each dictionary step whole)."""

    def __init__(self, rate_hz: float = RATE_HZ, bytes_per_s: float = BYTES_PER_S,
                 queued_max: int = QUEUED_BYTES_MAX, clock=time.monotonic):
        self.rate_hz, self.bytes_per_s, self.queued_max = rate_hz, bytes_per_s, queued_max
        self.clock = clock
        self._buckets: dict[str, _Bucket] = {}
        self._queued: Counter[str] = Counter()   # bytes per key waiting for the writer
        self.queued_bytes = 0
        self.dropped: Counter[tuple[str, str]] = Counter()
        self._max_samples, self._max_bytes = rate_hz * BURST_S, bytes_per_s * BURST_S
        self._half = queued_max // 2

    def admit(self, key: str, nbytes: int) -> str:
        """"" to queue the sample, else the reason it is dropped (counted). Hot: a few
        look-ups, no lock (one Zenoh thread per link calls it; a rare race between two links
        can only misplace a token, never let the queue grow without bound)."""
        now = self.clock()
        b = self._buckets.get(key)
        if b is None:
            b = self._buckets[key] = _Bucket(now, self._max_samples, self._max_bytes)
        dt = now - b.t
        if dt > 0.0:
            b.t = now
            b.samples = min(self._max_samples, b.samples + dt * self.rate_hz)
            b.bytes = min(self._max_bytes, b.bytes + dt * self.bytes_per_s)
        if b.samples < 1:
            why = OVER_RATE
        elif b.bytes < nbytes:
            why = OVER_BYTES
        elif self.queued_bytes + nbytes > self._half and self._over_share(key, nbytes):
            why = QUEUE_FULL
        else:
            b.samples -= 1
            b.bytes -= nbytes
            self._queued[key] += nbytes
            self.queued_bytes += nbytes
            return ""
        self.dropped[(key, why)] += 1
        return why

    def _over_share(self, key: str, nbytes: int) -> bool:
        active = sum(1 for v in self._queued.values() if v > 0) or 1
        return (self._queued[key] + nbytes > self.queued_max // (2 * active)
                or self.queued_bytes + nbytes > self.queued_max)

    def written(self, key: str, nbytes: int) -> None:
        """Queued bytes of ``key`` left the queue (written, or refused by the writer); the
        writer calls it once per key and batch."""
        left = self._queued[key] - nbytes
        if left <= 0:
            self._queued.pop(key, None)
        else:
            self._queued[key] = left
        self.queued_bytes -= nbytes

    def counts(self) -> dict[str, dict[str, int]]:
        """``{key: {reason: n}}`` of the dropped samples."""
        items = list(self.dropped.copy().items())
        out: dict[str, dict[str, int]] = {}
        for (key, why), n in items:
            out.setdefault(key, {})[why] = n
        return out
