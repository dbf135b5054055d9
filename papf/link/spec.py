"""What an emulated link does: its profiles, and the ``PROFILE|SPEC`` text that names one.

A :class:`LinkSpec` holds, per direction, a one-way delay (a floor) plus a random extra
delay (the jitter, given as quantiles of its distribution), a rate limit (serialization
delay), a loss rate (each lost chunk waits one TCP retransmission timeout), and outages —
on a schedule (``10@20``: 10 s from t = 20 s) or at random (seeded). Directions: ``out``
is the listening side towards ``--to`` (in ``papf run --link``: laptop -> robot), ``back``
the other way.

The profiles' figures and where each comes from: docs/link.md, "Profiles". Explicit
numbers always override a profile's: ``wifi,delay=20`` is Wi-Fi's jitter on a 20 ms floor.

SPEC text: items separated by commas, the first may be a profile name, the others
``key=value`` (keys :data:`KEYS`; ``outage`` may repeat), e.g. ``wifi-bad,outage=10@20``
or ``delay=200,jitter=150``.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace
from itertools import pairwise

from common.errors import ConfigError
from common.params import SEED, Spec, check_value, choice, num, unknown_name

OUTAGE_MODES = ("stall", "reset")
# stall: the TCP connections stay up and nothing moves (a Wi-Fi that lost its AP, a cable
# pulled): data waits, TCP resends it at its next retransmission (exponential backoff).
# reset: every connection through the link is reset when the outage starts and new ones are
# refused until it ends (a NAT or an AP that forgot the flows, a roaming address change).

Quantiles = tuple[tuple[float, float], ...]   # (probability, extra delay [ms]), 0 -> 1


@dataclass(frozen=True)
class LinkSpec:
    name: str = "custom"                 # the profile it came from
    delay_ms: float = 0.0                # one-way floor, each direction [ms]
    jitter: Quantiles = ((0.0, 0.0), (1.0, 0.0))   # extra one-way delay, quantiles [ms]
    jitter_period_ms: float = 100.0      # a jitter value holds this long (0: one per chunk)
    rate_kbit: float | None = None       # out direction [kbit/s]; None: unlimited
    rate_back_kbit: float | None = None  # back direction; None: as ``rate_kbit``
    loss_pct: float = 0.0                # chunks that wait one TCP retransmission timeout [%]
    outages: tuple[tuple[float, float], ...] = ()   # (length [s], start [s after t0])
    outage_mode: str = "stall"
    outage_rate_per_min: float = 0.0     # random outages per minute (Poisson), 0: none
    outage_mean_s: float = 2.0           # their mean length (exponential) [s]
    seed: int = 0

    @property
    def jitter_max_ms(self) -> float:
        return self.jitter[-1][1]

    def rate(self, direction: str) -> float | None:
        """The rate limit [kbit/s] of ``direction`` (``out`` or ``back``), None: unlimited."""
        if direction == "back" and self.rate_back_kbit is not None:
            return self.rate_back_kbit
        return self.rate_kbit

    def describe(self) -> str:
        """One line: ``wifi: 0.5 ms + jitter p50 1 / p90 9.5 / max 150 ms, 30 Mbit/s ...``."""
        parts = [f"{self.name}: {self.delay_ms:g} ms + {_jitter_text(self.jitter)} one way"]
        if self.rate_kbit is not None:
            back = self.rate("back")
            parts.append(f"{_rate_text(self.rate_kbit)}" + (
                f" out / {_rate_text(back)} back" if back != self.rate_kbit else ""))
        if self.loss_pct:
            parts.append(f"{self.loss_pct:g} % of chunks resent")
        for length, start in self.outages:
            parts.append(f"outage {length:g} s at t={start:g} s ({self.outage_mode})")
        if self.outage_rate_per_min:
            parts.append(f"random outages {self.outage_rate_per_min:g}/min, mean "
                         f"{self.outage_mean_s:g} s ({self.outage_mode})")
        return ", ".join(parts)

    def to_text(self) -> str:
        """The SPEC text that gives this spec back (:func:`parse_spec`)."""
        items = [f"delay={self.delay_ms:g}", "jitter=" + "/".join(
            f"{q:g}:{ms:g}" for q, ms in self.jitter), f"jitter_period={self.jitter_period_ms:g}"]
        if self.rate_kbit is not None:
            items.append(f"rate={self.rate_kbit:g}")
        if self.rate_back_kbit is not None:
            items.append(f"rate_back={self.rate_back_kbit:g}")
        items += [f"loss={self.loss_pct:g}", f"outage_mode={self.outage_mode}",
                  f"outage_rate={self.outage_rate_per_min:g}", f"outage_mean={self.outage_mean_s:g}",
                  f"seed={self.seed}", f"name={self.name}"]
        items += [f"outage={length:g}@{start:g}" for length, start in self.outages]
        return ",".join(items)

    def to_json(self) -> dict:
        d = asdict(self)
        d["jitter"] = [list(p) for p in self.jitter]
        d["outages"] = [{"length_s": length, "start_s": start} for length, start in self.outages]
        return d


def _rate_text(kbit: float | None) -> str:
    if kbit is None:
        return "unlimited"
    return f"{kbit / 1000:g} Mbit/s" if kbit >= 1000 else f"{kbit:g} kbit/s"


def _jitter_text(jitter: Quantiles) -> str:
    if len(jitter) == 2 and jitter[0] == (0.0, 0.0):
        return f"0-{jitter[1][1]:g} ms"
    inner = " / ".join(f"p{q * 100:g} {ms:g}" for q, ms in jitter if 0 < q < 1)
    return f"jitter {inner} / max {jitter[-1][1]:g} ms"


def uniform(jitter_ms: float) -> Quantiles:
    """Extra delay uniform in [0, ``jitter_ms``]."""
    return ((0.0, 0.0), (1.0, float(jitter_ms)))


def _from_one_way(points: Quantiles) -> tuple[float, Quantiles]:
    """A published one-way delay distribution (quantiles [ms]) as floor + jitter quantiles."""
    floor = points[0][1]
    return floor, tuple((q, ms - floor) for q, ms in points)


# One-way figures per direction. Sources (docs/link.md, "Profiles"): lan — 1000BASE-T
# (IEEE 802.3ab) and a switch hop's store-and-forward time; wifi — Sui et al., MobiSys 2016
# (Wi-Fi hop round trip p50 3 ms, p90 20 ms, p99 250 ms; halved); wifi-bad — Pei et al.,
# INFOCOM 2016 (over half the TCP packets > 20 ms on the Wi-Fi hop, a tenth > 100 ms,
# maxima of 250 ms; halved) at the lowest 802.11a/g OFDM rate; lte — Huang et al., MobiSys
# 2012 (median uplink 6 Mbit/s, downlink 13 Mbit/s; the ~70 ms RTT not yet checked: docs/link.md).
_WIFI_FLOOR, _WIFI_JITTER = _from_one_way(((0.0, 0.5), (0.5, 1.5), (0.9, 10.0), (0.99, 125.0),
                                           (1.0, 150.0)))
_BAD_FLOOR, _BAD_JITTER = _from_one_way(((0.0, 2.0), (0.5, 10.0), (0.9, 50.0), (1.0, 125.0)))
PROFILES: dict[str, LinkSpec] = {
    "lan": LinkSpec("lan", 0.1, uniform(0.1), rate_kbit=1_000_000.0),
    "wifi": LinkSpec("wifi", _WIFI_FLOOR, _WIFI_JITTER, rate_kbit=30_000.0),
    "wifi-bad": LinkSpec("wifi-bad", _BAD_FLOOR, _BAD_JITTER, rate_kbit=3_000.0),
    "lte": LinkSpec("lte", 25.0, uniform(20.0), rate_kbit=13_000.0, rate_back_kbit=6_000.0),
}

# key -> (field, declared range); the ranges are the command line's too (papf.cli.link)
MS = num(0.0, 60_000.0, "ms")
RATE = num(1.0, 1e8, "kbit/s")
LOSS = num(0.0, 50.0, "%")
OUTAGE_RATE = num(0.0, 60.0, "per minute")
OUTAGE_MEAN = num(0.01, 3600.0, "s")
JITTER_PERIOD = num(0.0, 10_000.0, "ms")
OUTAGE_LENGTH = num(0.01, 86_400.0, "s")
OUTAGE_START = num(0.0, 1e6, "s")
KEYS: dict[str, tuple[str, Spec]] = {
    "delay": ("delay_ms", MS), "jitter": ("jitter", MS),
    "jitter_period": ("jitter_period_ms", JITTER_PERIOD), "rate": ("rate_kbit", RATE),
    "rate_back": ("rate_back_kbit", RATE), "loss": ("loss_pct", LOSS),
    "outage": ("outages", OUTAGE_LENGTH), "outage_mode": ("outage_mode", choice(*OUTAGE_MODES)),
    "outage_rate": ("outage_rate_per_min", OUTAGE_RATE), "outage_mean": ("outage_mean_s", OUTAGE_MEAN),
    "seed": ("seed", SEED), "name": ("name", Spec(str)),
}


def parse_outage(text: str) -> tuple[float, float]:
    """``S@T`` -> (length S [s], start T [s]); ConfigError names the form."""
    length, sep, start = text.partition("@")
    if not sep:
        raise ConfigError(f"outage {text!r}: must be LENGTH@START in seconds, e.g. 10@20 "
                          "(10 s from t = 20 s)")
    return (check_value("outage length", length, OUTAGE_LENGTH),
            check_value("outage start", start, OUTAGE_START))


def parse_jitter(text: str) -> Quantiles:
    """``150`` (uniform 0-150 ms) or ``0:0/0.5:1/0.9:9.5/1:150`` (quantiles, as to_text writes)."""
    if "/" not in text and ":" not in text:
        return uniform(check_value("jitter", text, MS))
    points = []
    for item in text.split("/"):
        q, sep, ms = item.partition(":")
        if not sep:
            raise ConfigError(f"jitter {text!r}: must be MS, or quantiles P:MS/P:MS/... from P=0 "
                              "to P=1")
        points.append((check_value("jitter quantile", q, num(0.0, 1.0)),
                       check_value("jitter", ms, MS)))
    ok = (len(points) >= 2 and points[0][0] == 0.0 and points[-1][0] == 1.0
          and all(a[0] < b[0] and a[1] <= b[1] for a, b in pairwise(points)))
    if not ok:
        raise ConfigError(f"jitter {text!r}: quantiles must rise from P=0 to P=1 with delays "
                          "that never fall")
    return tuple(points)


def _value(key: str, text: str):
    field_name, spec = KEYS[key]
    if key == "jitter":
        return parse_jitter(text)
    if key == "outage":
        return parse_outage(text)
    if key == "name":
        return text.strip() or "custom"
    return check_value(key, text, spec)


def profile(name: str) -> LinkSpec:
    """A packaged profile by name (ConfigError with a "did you mean" otherwise)."""
    if name not in PROFILES:
        raise unknown_name(name, PROFILES, "link profile")
    return PROFILES[name]


def parse_spec(text: str) -> LinkSpec:
    """``PROFILE``, ``PROFILE,key=value,...`` or ``key=value,...`` as a :class:`LinkSpec`."""
    items = [t.strip() for t in text.split(",") if t.strip()]
    if not items:
        raise ConfigError("link spec is empty: give a profile (" + ", ".join(PROFILES)
                          + ") or key=value items, e.g. delay=200,jitter=150")
    spec = LinkSpec()
    if "=" not in items[0]:
        spec = profile(items.pop(0))
    overrides: dict = {}
    outages: list = []
    for item in items:
        key, sep, value = item.partition("=")
        key = key.strip().replace("-", "_")
        if not sep:
            raise ConfigError(f"link spec item {item!r}: must be key=value (keys: "
                              f"{', '.join(KEYS)}); a profile name only comes first")
        if key not in KEYS:
            raise unknown_name(key, KEYS, "link spec key")
        if key == "outage":
            outages.append(_value(key, value))
        else:
            overrides[key] = _value(key, value)
    return with_overrides(spec, outages=outages, **overrides)


def with_overrides(spec: LinkSpec, outages=(), **values) -> LinkSpec:
    """``spec`` with the given keys (:data:`KEYS`' names, checked values) replaced and
    ``outages`` added."""
    fields = {KEYS[k][0]: v for k, v in values.items() if v is not None}
    spec = replace(spec, **fields)
    if outages:
        spec = replace(spec, outages=tuple(sorted((*spec.outages, *outages), key=lambda o: o[1])))
    return check_spec(spec)


def check_spec(spec: LinkSpec) -> LinkSpec:
    """Every figure finite and in range (a spec built in code too); ConfigError otherwise."""
    for key, (field_name, rng) in KEYS.items():
        value = getattr(spec, field_name)
        if key in ("jitter", "outage", "name") or value is None:
            continue
        check_value(key, value, rng)
    for length, start in spec.outages:
        check_value("outage length", length, OUTAGE_LENGTH)
        check_value("outage start", start, OUTAGE_START)
    if not all(math.isfinite(ms) and 0 <= ms <= 60_000 for _, ms in spec.jitter):
        raise ConfigError(f"jitter {spec.jitter}: each delay must be in [0, 60000] ms")
    return spec
