"""The emulator's pure core: when each chunk of a TCP stream leaves the link (no sockets).

:class:`Direction` takes a chunk's arrival time and size and gives its delivery time:

- **rate**: the link serializes chunks one after the other: a chunk enters the link when
  the previous one has left the sender's side (``link_free``), and takes ``8 * size /
  rate`` seconds to go on the wire;
- **delay and jitter**: it arrives ``delay + jitter`` later; the jitter is drawn from the
  spec's quantiles (inverse CDF, linear between the points) once per ``jitter_period``
  (queueing delay changes at the pace of the queue, not per packet; 0: once per chunk),
  seeded by (seed, direction, period index), so a delivery depends only on the arrival
  times and sizes;
- **loss**: a lost chunk (``loss_pct``) waits one TCP retransmission timeout more
  (:func:`rto_estimate`);
- **one stream**: TCP delivers in order, so delivery times never fall: a chunk behind a
  slow one waits for it (head-of-line blocking, as TCP does);
- **outages** (:class:`OutageSchedule`): nothing is delivered inside one. ``stall``: a
  chunk that would enter the link or be in flight during an outage is sent again when
  TCP retries after it: retransmissions back off exponentially from the RTO (Linux:
  at least 200 ms, doubling, at most 120 s per wait), so a 10 s outage is over for TCP
  only at the first retry after it (12.6 s after it began with a 200 ms RTO).
  ``reset``: such a chunk is dropped (:meth:`Direction.depart` returns None) — the
  wrapper resets the connections when the outage begins.

Times are seconds on one monotonic clock; the outage schedule counts from its ``origin``
(t0: the emulator's start, or the moment ``papf run`` says its run started; ``inf``: not
yet, no outage happens).
"""

from __future__ import annotations

import bisect
import math
import random
from dataclasses import dataclass
from itertools import pairwise

from papf.link.spec import LinkSpec, Quantiles

RTO_MIN_S = 0.2           # Linux TCP_RTO_MIN (include/net/tcp.h)
RTO_MAX_S = 120.0         # Linux TCP_RTO_MAX
RANDOM_HORIZON_S = 600.0  # random outages are drawn this far ahead at a time [s]


@dataclass(frozen=True)
class Outage:
    start: float          # [s after origin]
    end: float
    random: bool = False  # drawn (outage_rate) rather than scheduled

    @property
    def length(self) -> float:
        return self.end - self.start


def merge(outages: list[Outage]) -> list[Outage]:
    """Overlapping or touching outages as one each, sorted by start."""
    out: list[Outage] = []
    for o in sorted(outages, key=lambda o: o.start):
        if out and o.start <= out[-1].end:
            last = out[-1]
            out[-1] = Outage(last.start, max(last.end, o.end), last.random and o.random)
        else:
            out.append(o)
    return out


class OutageSchedule:
    """The spec's outages — scheduled ones and random ones (a Poisson process of
    ``outage_rate_per_min``, exponential lengths of mean ``outage_mean_s``, drawn from the
    seed) — merged, in seconds after ``origin``."""

    def __init__(self, spec: LinkSpec, origin: float = 0.0):
        self.origin = origin
        self._fixed = [Outage(start, start + length) for length, start in spec.outages]
        self._rate = spec.outage_rate_per_min / 60.0          # [1/s]
        self._mean = spec.outage_mean_s
        self._rng = random.Random(f"{spec.seed}/outages")
        self._random: list[Outage] = []
        self._drawn_until = 0.0
        self._next = self._rng.expovariate(self._rate) if self._rate > 0 else float("inf")
        self.intervals = merge(self._fixed)
        self._starts = [o.start for o in self.intervals]

    def _draw(self, until: float) -> None:
        """Random outages beginning before ``until`` (deterministic: drawn in order)."""
        if self._rate <= 0 or until <= self._drawn_until:
            return
        self._drawn_until = until + RANDOM_HORIZON_S
        while self._next < self._drawn_until:
            length = self._rng.expovariate(1.0 / self._mean)
            self._random.append(Outage(self._next, self._next + length, random=True))
            self._next += length + self._rng.expovariate(self._rate)
        self.intervals = merge(self._fixed + self._random)
        self._starts = [o.start for o in self.intervals]

    def at(self, t: float) -> Outage | None:
        """The outage that holds clock time ``t`` (start inclusive, end exclusive), or None."""
        rel = t - self.origin
        self._draw(rel)
        i = bisect.bisect_right(self._starts, rel) - 1
        return self.intervals[i] if i >= 0 and rel < self.intervals[i].end else None

    def between(self, t0: float, t1: float) -> Outage | None:
        """The first outage that holds a moment of [``t0``, ``t1``] (clock times), or None."""
        found = self.at(t0)
        if found is not None:
            return found
        rel0, rel1 = t0 - self.origin, t1 - self.origin
        self._draw(rel1)
        i = bisect.bisect_right(self._starts, rel0)
        return self.intervals[i] if i < len(self.intervals) and self._starts[i] <= rel1 else None

    def until(self, t: float) -> list[Outage]:
        """Every outage that began before clock time ``t``."""
        rel = t - self.origin
        self._draw(rel)
        return [o for o in self.intervals if o.start < rel]

    def clock(self, rel: float) -> float:
        """Clock time of ``rel`` seconds after the origin."""
        return self.origin + rel


def resume_after(outage: Outage, rto_s: float) -> float:
    """When TCP's first retransmission after ``outage`` goes (seconds after origin): the
    retries come ``rto, 2 rto, 4 rto, ...`` (each wait at most :data:`RTO_MAX_S`) after
    the outage began."""
    t, wait = outage.start, rto_s
    while t < outage.end:
        t += wait
        wait = min(2.0 * wait, RTO_MAX_S)
    return t


def rto_estimate(spec: LinkSpec) -> float:
    """The retransmission timeout [s] a Linux TCP sender settles on over this link (RFC 6298:
    ``srtt + 4 rttvar``, at least :data:`RTO_MIN_S`): ``srtt`` the mean round trip (twice the
    delay and the mean jitter), ``rttvar`` the mean deviation of the round trip (two
    independent one-way jitters: about sqrt(2) times one's mean deviation)."""
    us = [(k + 0.5) / 1000.0 for k in range(1000)]
    js = [quantile(spec.jitter, u) for u in us]
    mean = sum(js) / len(js)
    dev = sum(abs(j - mean) for j in js) / len(js)
    srtt_ms = 2.0 * (spec.delay_ms + mean)
    return max(RTO_MIN_S, (srtt_ms + 4.0 * math.sqrt(2.0) * dev) / 1000.0)


def quantile(points: Quantiles, u: float) -> float:
    """The value at probability ``u`` of a distribution given by quantile points
    (linear between them)."""
    for (q0, v0), (q1, v1) in pairwise(points):
        if u <= q1:
            return v0 if q1 == q0 else v0 + (v1 - v0) * (u - q0) / (q1 - q0)
    return points[-1][1]


class Direction:
    """The delivery schedule of one direction (``out`` or ``back``) of a link."""

    def __init__(self, spec: LinkSpec, direction: str, outages: OutageSchedule):
        self.spec, self.direction, self.outages = spec, direction, outages
        rate = spec.rate(direction)
        self.byte_s = 0.0 if rate is None else 8.0 / (rate * 1000.0)   # [s per byte]
        self.delay_s = spec.delay_ms / 1000.0
        self.period_s = spec.jitter_period_ms / 1000.0
        self.rto_s = rto_estimate(spec)
        self._chunk_rng = random.Random(f"{spec.seed}/{direction}/chunks")
        self._slot: tuple[int, float] | None = None
        # jitter periods count from here (the outages' origin may be unset: t0 on a signal)
        self.slot_origin = outages.origin if outages.origin != float("inf") else 0.0
        self.link_free = float("-inf")   # when the previous chunk is all on the wire
        self.last = float("-inf")        # the previous chunk's delivery
        self.dropped = 0                 # chunks dropped in reset-mode outages
        self.lost = 0                    # chunks that waited a retransmission timeout

    def jitter_s(self, t: float) -> float:
        """The extra one-way delay [s] of a chunk entering the link at clock time ``t``."""
        if self.spec.jitter_max_ms <= 0.0:
            return 0.0
        if self.period_s <= 0.0:
            u = self._chunk_rng.random()
        else:
            slot = int((t - self.slot_origin) // self.period_s)
            if self._slot is None or self._slot[0] != slot:
                u = random.Random(f"{self.spec.seed}/{self.direction}/{slot}").random()
                self._slot = (slot, u)
            u = self._slot[1]
        return quantile(self.spec.jitter, u) / 1000.0

    def _in_flight(self, entry: float, size: int) -> float:
        lost = self.spec.loss_pct > 0 and self._chunk_rng.random() * 100.0 < self.spec.loss_pct
        self.lost += lost
        return entry + size * self.byte_s + self.delay_s + self.jitter_s(entry) + (
            self.rto_s if lost else 0.0)

    def depart(self, t: float, size: int) -> float | None:
        """Delivery time of a chunk of ``size`` bytes that reached the link at clock time
        ``t``; None if a reset-mode outage drops it. Never earlier than the previous one."""
        entry = max(t, self.link_free)
        delivery = self._in_flight(entry, size)
        while (outage := self.outages.between(entry, delivery)) is not None:
            if self.spec.outage_mode == "reset":
                self.dropped += 1
                return None
            entry = self.outages.clock(resume_after(outage, self.rto_s))
            delivery = self._in_flight(entry, size)
        self.link_free = entry + size * self.byte_s
        self.last = max(delivery, self.last)
        return self.last
