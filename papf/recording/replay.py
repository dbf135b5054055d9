"""Republish a recording with its timing: ``papf replay run.mcap --rate 2`` (docs/recording.md).

:func:`replay` puts payloads back on their recorded keys (or another namespace's) byte for
byte, in log-time order, paced by ``rate``; a rosbag2 from the robot is replayed as our
messages. Pure: the caller passes the publish function. Used by ``papf replay``.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from common.errors import RecordingError
from papf.recording.reader import Recording
from papf.recording.rosbag import BagRecording, TopicMap, open_run
from schemas.keys import TOPICS

MAX_GAP_S = 5.0         # [s] of log time; longest pause replayed (see replay())
STOP_POLL_S = 0.1       # [s] longest sleep between checks of stop()
PROGRESS_EVERY_S = 0.1  # [s] wall time between progress calls

Publish = Callable[[str, bytes], None]


@dataclass
class ReplayStats:
    messages: int = 0
    skipped_keys: dict[str, int] = field(default_factory=dict)   # recorded key -> messages
    bytes: int = 0
    log_span_s: float = 0.0      # recorded time covered [s]
    wall_s: float = 0.0          # how long the replay took [s]
    per_key: dict[str, int] = field(default_factory=dict)


def recorded_namespace(rec: Recording | BagRecording) -> str | None:
    """The namespace a recording was made under: its ``run`` metadata ``namespace``,
    else the prefix of the first key that ends in a stack topic (``rosbot/scan``)."""
    ns = rec.run_metadata.get("namespace")
    if ns:
        return ns
    suffixes = sorted(TOPICS, key=len, reverse=True)
    for key in rec.keys():
        for suffix in suffixes:
            if key.endswith("/" + suffix):
                return key[: -len(suffix) - 1]
    return None


_NOT_IN_KEYS = set("*$?#")


def zenoh_key(topic: str) -> str | None:
    """The Zenoh key a recorded topic is replayed on (``/a/b`` -> ``a/b``), or None."""
    key = topic[1:] if topic.startswith("/") else topic
    if not key or key.endswith("/") or "//" in key or _NOT_IN_KEYS & set(key):
        return None
    return key


def key_namespace(key: str) -> str:
    """The namespace a key is under: the part before a stack topic (``lab/r1/scan`` ->
    ``lab/r1``), else its first chunk."""
    for suffix in sorted(TOPICS, key=len, reverse=True):
        if key.endswith("/" + suffix) and len(key) > len(suffix) + 1:
            return key[: -len(suffix) - 1]
    return key.split("/")[0]


def target_namespaces(rec: Recording | BagRecording, keys=None, namespace: str | None = None) -> set[str]:
    """Namespaces a replay of ``rec`` would publish under, from the keys themselves as
    :func:`replay` remaps them (a metadata namespace that differs from the keys must not
    hide where the messages go)."""
    old_ns = recorded_namespace(rec) if namespace else None
    out = {key_namespace(k) for k in (zenoh_key(remap_key(k, old_ns, namespace))
                                      for k in rec.keys(keys)) if k}
    return out or ({namespace} if namespace else set())


def check_rate(rate: float | None) -> None:
    """RecordingError unless ``rate`` is None, 0 (as fast as possible) or a finite number > 0."""
    if rate is not None and not (math.isfinite(rate) and rate >= 0):
        raise RecordingError(f"replay rate {rate} must be a finite number > 0 "
                             "(or 0 for as fast as possible)")


def remap_key(key: str, old_ns: str | None, new_ns: str | None) -> str:
    """``rosbot/scan`` -> ``r2/scan`` for old ``rosbot``, new ``r2``; other keys unchanged."""
    if not new_ns or not old_ns or not key.startswith(old_ns + "/"):
        return key
    return new_ns + key[len(old_ns):]


class _Publishers:
    """Adapts a publish function or a Zenoh-like session (one publisher per key)."""

    def __init__(self, target: Any):
        self._fn: Publish | None = None
        self._session = None
        self._pubs: dict[str, Any] = {}
        if hasattr(target, "declare_publisher"):
            self._session = target
        elif callable(target):
            self._fn = target
        else:
            raise RecordingError(f"replay target {target!r} is neither a publish function "
                                 f"(key, payload) nor a session with declare_publisher()")

    def prepare(self, keys: Iterable[str]) -> None:
        """Declare publishers up front so the first messages are not late."""
        if self._session is not None:
            for key in keys:
                if key not in self._pubs:
                    self._pubs[key] = self._session.declare_publisher(key)

    def put(self, key: str, data: bytes) -> None:
        if self._fn is not None:
            self._fn(key, data)
            return
        pub = self._pubs.get(key)
        if pub is None:
            pub = self._pubs[key] = self._session.declare_publisher(key)
        pub.put(data)

    def close(self) -> None:
        for pub in self._pubs.values():
            pub.undeclare()
        self._pubs.clear()


class _Pacer:
    """Waits until log time ``t`` is due: ``(t - t_0) / rate`` after the start, gaps clamped."""

    def __init__(self, rate: float | None, max_gap_s: float, stop: Callable[[], bool],
                 clock: Callable[[], float], sleep: Callable[[float], None]):
        self.rate, self.max_gap_s, self.stop, self.clock, self.sleep = (
            rate, max_gap_s, stop, clock, sleep)
        self.start = clock()
        self.span_s = 0.0  # [s] of (clamped) log time covered so far
        self._last_ns: int | None = None

    def wait(self, log_time_ns: int) -> None:
        if self._last_ns is not None:
            gap_s = (log_time_ns - self._last_ns) / 1e9
            self.span_s += min(max(gap_s, 0.0), self.max_gap_s)
        self._last_ns = log_time_ns
        if not self.rate:
            return
        due = self.start + self.span_s / self.rate
        while not self.stop():
            delay = due - self.clock()
            if delay <= 0:
                return
            self.sleep(min(delay, STOP_POLL_S))


def replay(path: str | Path, target: Publish | Any, rate: float | None = 1.0,
           keys: str | Iterable[str] | None = None, namespace: str | None = None, *,
           progress: Callable[[int, int], None] | None = None,
           stop: Callable[[], bool] = lambda: False, max_gap_s: float = MAX_GAP_S,
           clock: Callable[[], float] = time.monotonic,
           sleep: Callable[[float], None] = time.sleep,
           topics: TopicMap | None = None) -> ReplayStats:
    """Republish ``path`` on ``target``.

    ``keys``: key expression(s) of the recorded keys to replay (default all);
    ``namespace``: publish under this namespace instead of the recorded one;
    ``progress(done, total)`` is called about ten times a second; ``stop()`` aborts;
    ``topics``: a rosbag2's topic names (it is replayed as our messages on our keys).

    Payloads are put back on their recorded keys (or the same topics under another
    namespace) byte for byte, in log-time order. Message ``i`` goes out
    ``(log_i - log_0) / rate`` seconds after the first; ``rate`` None or 0 sends as fast
    as possible. Log time is the messages' ``stamp_ns`` (sim time), so a lockstep run
    that took 5 s of wall time for 60 s of sim time replays over 60 s at rate 1.

    Recorded keys that are not Zenoh keys are mapped the way ``zenoh-bridge-ros2dds`` maps
    ROS 2 topic names (``/some/topic`` -> ``some/topic``); a key that still is not one
    (empty chunks, wildcards) is skipped and counted, never a crash.

    A jump in log time longer than ``max_gap_s`` (e.g. from sim-time stamps to messages
    stamped with their wall-clock receive time, which had no ``stamp_ns``) is replayed
    as ``max_gap_s``, so one odd stamp cannot stall a replay for decades.

    A rosbag2 from the robot (:mod:`papf.recording.rosbag`) is replayed as our messages on
    our keys, msgpack-encoded, so the stack's nodes take it (the energy meter re-meters it,
    the viewer shows it).

    Pure: the caller passes a publish function ``(key, payload) -> None`` or anything
    with ``declare_publisher(key)`` (a Zenoh session); no Zenoh import here.
    """
    check_rate(rate)
    stats = ReplayStats()
    publishers = _Publishers(target)
    with open_run(path, topics) as rec:
        old_ns = recorded_namespace(rec) if namespace else None
        counts = rec.counts()
        total = sum(counts.get(k, 0) for k in rec.keys(keys))
        valid = {k: zenoh_key(remap_key(k, old_ns, namespace)) for k in rec.keys(keys)}
        try:
            publishers.prepare(k for k in valid.values() if k)
            pacer = _Pacer(rate, max_gap_s, stop, clock, sleep)
            next_progress = pacer.start
            for raw in rec.raw(keys):
                key = valid.get(raw.key)
                if key is None:
                    stats.skipped_keys[raw.key] = stats.skipped_keys.get(raw.key, 0) + 1
                    continue
                pacer.wait(raw.log_time_ns)
                if stop():
                    break
                publishers.put(key, raw.data)
                stats.messages += 1
                stats.bytes += len(raw.data)
                stats.per_key[key] = stats.per_key.get(key, 0) + 1
                if progress is not None and clock() >= next_progress:
                    progress(stats.messages, total)
                    next_progress = clock() + PROGRESS_EVERY_S
        finally:
            publishers.close()
    stats.log_span_s, stats.wall_s = pacer.span_s, clock() - pacer.start
    if progress is not None:
        progress(stats.messages, total)
    return stats
