"""Write a run to MCAP, crash-safe (docs/recording.md). Pure: no Zenoh here.

:class:`RunWriter` writes one channel per key (schemas for the stack's messages), log
time = the message's stamp, a ``run`` metadata record; chunks are flushed often so a
SIGKILL loses little (``papf recover`` salvages the rest). Used by the recorder node.
"""

from __future__ import annotations

import json
import platform
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import msgpack
from mcap.writer import CompressionType, Writer

import common
from common.errors import RecordingError
from common.outfiles import exclusive
from schemas.base import Message
from schemas.keys import TOPICS

MESSAGE_ENCODING = "msgpack"
RAW_ENCODING = "application/octet-stream"
SCHEMA_ENCODING = "jsonschema"
RUN_METADATA = "run"
NOT_RECORDED = "not_recorded"   # metadata: {key: {reason: n}} of samples the recorder refused
MAX_NAMED_KEYS = 1000           # [-] keys named in it (a hostile peer may use millions)
PROFILE = "papf"  # MCAP header profile: our own conventions (RunWriter's docstring)

# Defaults. A chunk is closed at whichever limit comes first.
FLUSH_INTERVAL_S = 0.2      # [s] wall time; bounds what a SIGKILL can lose
CHUNK_SIZE = 512 * 1024     # [bytes] uncompressed
MAX_CHANNELS = 10_000      # [-] distinct keys recorded (MCAP channel ids are 16-bit); more: dropped, counted
PEEK_FULL_UNPACK_MAX = 256  # [bytes] below this, unpacking the whole map is the cheapest peek
COMPRESSIONS = {"none": CompressionType.NONE, "lz4": CompressionType.LZ4,
                "zstd": CompressionType.ZSTD}


def type_for_key(key: str) -> type[Message] | None:
    """Message type of a full key whose suffix is a stack topic (any namespace), else None.

    ``rosbot/scan`` -> Scan, ``lab/r1/planner/state`` -> PlannerState, ``x/y`` -> None.
    """
    parts = key.split("/")
    for i in range(1, len(parts)):  # longest suffix first, namespace at least one chunk
        msg_type = TOPICS.get("/".join(parts[i:]))
        if msg_type is not None:
            return msg_type
    return None


def peek_stamp(data: bytes) -> int | None:
    """``stamp_ns`` of a msgpack map payload without decoding the whole map, or None.

    Cheap for big payloads (scans, planner states): reads the map header and the first
    few entries only (our encoder writes ``_type`` then ``stamp_ns``). None when the
    payload is not a msgpack map, has no integer stamp, or the stamp does not fit
    MCAP's unsigned 64-bit log time.
    """
    try:
        if len(data) <= PEEK_FULL_UNPACK_MAX:
            wire = msgpack.unpackb(data, raw=False)
            stamp = wire.get("stamp_ns") if type(wire) is dict else None
        else:
            stamp = _peek_large(data)
    except Exception:  # any malformed payload: no stamp
        return None
    if type(stamp) is int and 0 <= stamp < 2**64:
        return stamp
    return None


def _peek_large(data: bytes, max_entries: int = 4) -> Any:
    unpacker = msgpack.Unpacker(raw=False)
    unpacker.feed(data)
    for _ in range(min(unpacker.read_map_header(), max_entries)):
        if unpacker.unpack() == "stamp_ns":
            return unpacker.unpack()
        unpacker.skip()
    return None


def is_msgpack(data: bytes) -> bool:
    """True if ``data`` is exactly one msgpack object."""
    try:
        msgpack.unpackb(data, raw=False, strict_map_key=False)
    except Exception:
        return False
    return True


def default_metadata() -> dict[str, str]:
    """What every recording states about the software that made it."""
    return {"software": "papf-stack", "software_version": common.__version__,
            "python": platform.python_version(), "created_unix_ns": str(time.time_ns())}


def metadata_strings(metadata: Mapping[str, Any]) -> dict[str, str]:
    """MCAP metadata values are strings: keep str as is, JSON-encode the rest."""
    return {str(k): v if isinstance(v, str) else json.dumps(v, sort_keys=True, default=str)
            for k, v in metadata.items()}


@dataclass
class WriterStats:
    messages: int = 0
    bytes: int = 0           # payload bytes
    unstamped: int = 0       # messages logged at their receive time (no stamp_ns)
    channels: int = 0
    dropped: int = 0         # messages on keys beyond MAX_CHANNELS, not recorded
    dropped_keys: int = 0    # distinct such keys seen (counted up to MAX_CHANNELS more)


class RunWriter:
    """An MCAP recording being written. Use as a context manager or call :meth:`close`.

    ``RunWriter(path, {"world": "energy", "planner": planner, "seed": 1})`` then
    ``write(key, payload)`` for every received sample; ``maybe_flush()`` on idle ticks.

    Layout of a recording (see docs/recording.md):

    - one channel per Zenoh key (topic = the full key, e.g. ``rosbot/scan``), message
      encoding ``msgpack``; keys of the stack (``schemas.keys.TOPICS``) get a schema
      record named after the message type (``papf/Scan/v1``, encoding ``jsonschema``,
      data = ``Message.json_schema()`` as JSON); any other key is recorded raw with no
      schema (id 0) and encoding ``msgpack`` if its first payload is msgpack, else
      ``application/octet-stream``;
    - ``log_time`` = the message's ``stamp_ns`` (sim time in sim runs; the receive wall
      time when the payload has none), so log times may go backwards across channels;
      ``publish_time`` = the wall-clock receive time [ns since the Unix epoch];
    - a metadata record named ``run`` (world, planner, seed, parameters, versions).

    Hostile keys: at most :data:`MAX_CHANNELS` channels; messages on further keys are counted
    (``stats.dropped``, and a ``dropped`` metadata record at the end), never recorded, so any
    number of distinct keys leaves a complete file with its footer.

    Crash safety: messages go into chunks that are closed and flushed to the OS at
    least every ``flush_interval_s`` of wall time (and when ``chunk_size`` bytes are
    buffered), so a SIGKILL loses at most that much; ``papf recover`` salvages the rest.
    """

    def __init__(self, path: str | Path, metadata: Mapping[str, Any] | None = None, *,
                 compression: str = "zstd", chunk_size: int = CHUNK_SIZE,
                 flush_interval_s: float = FLUSH_INTERVAL_S,
                 clock: Callable[[], float] = time.monotonic, force: bool = False,
                 max_channels: int | None = None):
        if compression not in COMPRESSIONS:
            raise RecordingError(f"compression {compression!r} is not one of {list(COMPRESSIONS)}")
        if flush_interval_s <= 0:
            raise RecordingError(f"flush interval {flush_interval_s} s must be > 0")
        self.path = Path(path)
        try:   # a new file only: never over a user's file, never through a symlink
            self._file = exclusive(self.path, force)
        except OSError as exc:
            raise RecordingError(f"cannot create recording {str(path)!r}: {exc}") from None
        self._mcap = Writer(self._file, chunk_size=chunk_size,
                            compression=COMPRESSIONS[compression])
        self._mcap.start(profile=PROFILE, library=f"papf-stack/{common.__version__}")
        self._mcap.add_metadata(RUN_METADATA, metadata_strings({**default_metadata(),
                                                               **(metadata or {})}))
        self._file.flush()
        self._channels: dict[str, int] = {}
        self._schemas: dict[str, int] = {}
        self._max_channels = MAX_CHANNELS if max_channels is None else max_channels
        self._dropped_keys: set[str] = set()
        self._clock, self._interval = clock, flush_interval_s
        self._last_flush = clock()
        self._dirty = False
        self._last_stamp_ns: int | None = None  # [ns] log time of unstamped payloads
        self.stats = WriterStats()
        self.dropped_by_key: dict[str, dict[str, int]] = {}   # the recorder's bounds and seals
        self.closed = False

    def __enter__(self) -> RunWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- writing ----------------------------------------------------------
    def write(self, key: str, data: bytes, receive_ns: int | None = None,
              log_time_ns: int | None = None) -> None:
        """Record one payload received on ``key``.

        ``receive_ns``: wall-clock receive time [ns since epoch] (default: now).
        ``log_time_ns``: override; by default the payload's ``stamp_ns``, else the last
        stamp seen (so garbage and unstamped payloads sit where they arrived on the sim-time
        line), else ``receive_ns`` when nothing stamped came yet.
        """
        if receive_ns is None:
            receive_ns = time.time_ns()
        channel = self._channels.get(key)
        if channel is None:
            if len(self._channels) >= self._max_channels:
                self._drop(key)
                return
            channel = self._add_channel(key, data)
        if log_time_ns is None:
            log_time_ns = peek_stamp(data)
            if log_time_ns is None:
                log_time_ns = receive_ns if self._last_stamp_ns is None else self._last_stamp_ns
                self.stats.unstamped += 1
            else:
                self._last_stamp_ns = log_time_ns
        self._mcap.add_message(channel, log_time_ns, data, receive_ns)
        self.stats.messages += 1
        self.stats.bytes += len(data)
        self._dirty = True
        if self._clock() - self._last_flush >= self._interval:
            self.flush()

    def _drop(self, key: str) -> None:
        """A message on a key past :data:`MAX_CHANNELS`: counted, not recorded."""
        self.stats.dropped += 1
        if len(self._dropped_keys) < self._max_channels and key not in self._dropped_keys:
            self._dropped_keys.add(key)
            self.stats.dropped_keys = len(self._dropped_keys)

    def write_message(self, key: str, msg: Message, receive_ns: int | None = None) -> None:
        """Record a typed message (tests, tools): same as ``write(key, msg.to_bytes())``."""
        self.write(key, msg.to_bytes(), receive_ns)

    def _add_channel(self, key: str, first_payload: bytes) -> int:
        msg_type = type_for_key(key)
        if msg_type is None:
            schema_id = 0
            encoding = MESSAGE_ENCODING if is_msgpack(first_payload) else RAW_ENCODING
        else:
            schema_id = self._schema_id(msg_type)
            encoding = MESSAGE_ENCODING
        channel = self._mcap.register_channel(key, encoding, schema_id)
        self._channels[key] = channel
        self.stats.channels += 1
        return channel

    def _schema_id(self, msg_type: type[Message]) -> int:
        schema_id = self._schemas.get(msg_type.TYPE)
        if schema_id is None:
            data = json.dumps(msg_type.json_schema(), sort_keys=True).encode()
            schema_id = self._mcap.register_schema(msg_type.TYPE, SCHEMA_ENCODING, data)
            self._schemas[msg_type.TYPE] = schema_id
        return schema_id

    def add_metadata(self, name: str, values: Mapping[str, Any]) -> None:
        """Another metadata record (e.g. ``"result"`` with the run's outcome at the end)."""
        self._mcap.add_metadata(name, metadata_strings(values))
        self._file.flush()

    # -- flushing and closing ---------------------------------------------
    def maybe_flush(self) -> None:
        """Flush if the flush interval has passed since the last flush (call on idle ticks)."""
        if self._dirty and self._clock() - self._last_flush >= self._interval:
            self.flush()

    def flush(self) -> None:
        """Close the current chunk and hand everything to the OS (survives a SIGKILL)."""
        self._mcap.flush()
        self._last_flush = self._clock()
        self._dirty = False

    def abandon(self) -> None:
        """Stop writing without a summary (the disk is full, say): what reached the disk
        stays, a truncated recording that ``papf recover`` salvages."""
        if self.closed:
            return
        self.closed = True
        try:
            self._file.close()
        except OSError:
            pass

    def close(self) -> None:
        """Write the summary (indexes, statistics) and the footer; the file is then complete."""
        if self.closed:
            return
        self.closed = True
        try:
            if self.stats.dropped:
                self._mcap.add_metadata("dropped", metadata_strings(
                    {"messages": self.stats.dropped, "keys": self.stats.dropped_keys,
                     "max_channels": self._max_channels}))
            if self.dropped_by_key:   # not recorded: refused seals, over a key's budget
                self._mcap.add_metadata(NOT_RECORDED, metadata_strings(
                    {key: why
                     for key, why in sorted(self.dropped_by_key.items())[:MAX_NAMED_KEYS]}))
            self._mcap.finish()
        finally:
            self._file.close()
