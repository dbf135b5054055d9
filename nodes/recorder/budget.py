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

import threading
import time
from collections import Counter

RATE_HZ = 5_000                  # [1/s] samples per key (lockstep odometry: ~1,000/s)
BYTES_PER_S = 16 * 1024 * 1024   # [B/s] per key
BURST_S = 2.0                    # [s] of budget a quiet key saves up
QUEUED_BYTES_MAX = 64 * 1024 * 1024   # [B] waiting for the writer, all keys together
OVER_RATE, OVER_BYTES, QUEUE_FULL = "rate", "bytes", "queue"


class _Bucket:
    __slots__ = ("samples", "bytes", "t")

    def __init__(self, now: float):
        self.samples, self.bytes, self.t = RATE_HZ * BURST_S, BYTES_PER_S * BURST_S, now


class Budget:
    """Admission of samples per key (module doc). Thread-safe: :meth:`admit` runs on Zenoh's
    thread, :meth:`written` on the writer's."""

    def __init__(self, rate_hz: float = RATE_HZ, bytes_per_s: float = BYTES_PER_S,
                 queued_max: int = QUEUED_BYTES_MAX, clock=time.monotonic):
        self.rate_hz, self.bytes_per_s, self.queued_max = rate_hz, bytes_per_s, queued_max
        self.clock = clock
        self._buckets: dict[str, _Bucket] = {}
        self._queued: Counter[str] = Counter()   # bytes per key waiting for the writer
        self.queued_bytes = 0
        self.dropped: Counter[tuple[str, str]] = Counter()
        self._lock = threading.Lock()

    def admit(self, key: str, nbytes: int) -> str:
        """"" to queue the sample, else the reason it is dropped (counted)."""
        now = self.clock()
        with self._lock:
            b = self._buckets.get(key)
            if b is None:
                b = self._buckets[key] = _Bucket(now)
            dt = max(0.0, now - b.t)
            b.t = now
            b.samples = min(self.rate_hz * BURST_S, b.samples + dt * self.rate_hz)
            b.bytes = min(self.bytes_per_s * BURST_S, b.bytes + dt * self.bytes_per_s)
            why = self._why(key, b, nbytes)
            if why:
                self.dropped[(key, why)] += 1
                return why
            b.samples -= 1
            b.bytes -= nbytes
            self._queued[key] += nbytes
            self.queued_bytes += nbytes
            return ""

    def _why(self, key: str, b: _Bucket, nbytes: int) -> str:
        if b.samples < 1:
            return OVER_RATE
        if b.bytes < nbytes:
            return OVER_BYTES
        if self.queued_bytes + nbytes > self.queued_max // 2:
            active = sum(1 for v in self._queued.values() if v > 0) or 1
            share = self.queued_max // (2 * active)
            if self._queued[key] + nbytes > share or self.queued_bytes + nbytes > self.queued_max:
                return QUEUE_FULL
        return ""

    def written(self, key: str, nbytes: int) -> None:
        """A queued sample left the queue (written, or refused by the writer)."""
        with self._lock:
            self._queued[key] -= nbytes
            if self._queued[key] <= 0:
                del self._queued[key]
            self.queued_bytes -= nbytes

    def counts(self) -> dict[str, dict[str, int]]:
        """``{key: {reason: n}}`` of the dropped samples."""
        with self._lock:
            items = list(self.dropped.items())
        out: dict[str, dict[str, int]] = {}
        for (key, why), n in items:
            out.setdefault(key, {})[why] = n
        return out
