"""Read a recording made by :mod:`nodes.recorder.writer` (docs/recording.md).

``with open_recording("run.mcap") as rec:`` then ``rec.run_metadata`` and
``for key, msg, log_time_ns in rec.messages(): ...`` — ``msg`` is the decoded
:class:`~schemas.base.Message` when the channel's schema names a known message
type and the payload is valid, else the raw payload bytes.

A file that is not a complete MCAP (the recorder was killed, the disk filled up, a
copy was cut short) raises :class:`~common.errors.RecordingError` telling the user to
run ``papf recover``.
"""

from __future__ import annotations

import io
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import NamedTuple

from mcap.reader import make_reader

from common.errors import RecordingError, SchemaError
from nodes.recorder.writer import RUN_METADATA
from papf.recording.bounds import check_file_chunks
from papf.recording.scan import open_regular
from schemas.base import Message
from schemas.messages import BY_TYPE

MAGIC = b"\x89MCAP0\r\n"


class RawMessage(NamedTuple):
    """A recorded payload as stored: times in integer nanoseconds."""

    key: str
    data: bytes
    log_time_ns: int      # stamp_ns of the message (or receive time if it had none)
    publish_time_ns: int  # wall-clock receive time, ns since the Unix epoch
    schema_name: str      # message type (``papf/Scan/v1``) or "" for raw channels
    encoding: str         # channel message encoding


class RecordedMessage(NamedTuple):
    key: str
    message: Message | bytes
    log_time_ns: int


def key_matches(expr: str, key: str) -> bool:
    """Zenoh-style key expression match: ``*`` = one chunk, ``**`` = any number of chunks."""
    return _match(tuple(expr.split("/")), tuple(key.split("/")))


def _match(pat: tuple[str, ...], parts: tuple[str, ...]) -> bool:
    if not pat:
        return not parts
    head, rest = pat[0], pat[1:]
    if head == "**":
        return any(_match(rest, parts[i:]) for i in range(len(parts) + 1))
    if not parts:
        return False
    return (head == "*" or head == parts[0]) and _match(rest, parts[1:])


def decode(schema_name: str, data: bytes) -> Message | bytes:
    """The message a payload holds, or the payload itself if it is unknown or invalid."""
    msg_type = BY_TYPE.get(schema_name)
    if msg_type is None:
        return data
    try:
        return msg_type.from_bytes(data)
    except SchemaError:
        return data


def truncated_error(path: Path, exc: BaseException | str) -> RecordingError:
    """The RecordingError of a cut-short file, saying how to salvage it."""
    return RecordingError(
        f"{path}: not a complete MCAP recording ({exc}); it was probably cut short "
        f"(recorder killed, disk full). Salvage it with: papf recover {path} FIXED.mcap")


class Recording:
    """An open, complete recording. Iterators may be used one after another."""

    def __init__(self, path: str | Path):
        self.path = Path(path)
        self._file = open_regular(self.path)
        try:
            self._check_ends()
            self._reader = make_reader(self._file, validate_crcs=True)
            self.summary = self._reader.get_summary()
            if self.summary is not None:   # before any chunk is decompressed
                self._check_chunks()
            self.metadata = {m.name: dict(m.metadata) for m in self._reader.iter_metadata()}
        except RecordingError:
            self.close()
            raise
        except Exception as exc:  # mcap/struct/zstd errors alike: a broken file
            self.close()
            raise truncated_error(self.path, exc) from None
        if self.summary is None:  # a valid MCAP whose writer chose no summary: not ours
            self.close()
            raise RecordingError(f"{self.path}: MCAP has no summary section; "
                                 f"rewrite it with: papf recover {self.path} FIXED.mcap")

    def _check_chunks(self) -> None:
        """Every chunk within :data:`papf.recording.bounds.MAX_CHUNK_BYTES`, and indexed (the
        library would read unindexed chunks one by one, unchecked)."""
        stats, indexes = self.summary.statistics, self.summary.chunk_indexes
        if stats is not None and stats.chunk_count > len(indexes):
            raise RecordingError(f"{self.path}: {stats.chunk_count} chunks but {len(indexes)} "
                                 f"indexed; rewrite it with: papf recover {self.path} FIXED.mcap")
        check_file_chunks(self._file, indexes, str(self.path))

    def _check_ends(self) -> None:
        head = self._file.read(len(MAGIC))
        if len(head) < len(MAGIC) and MAGIC.startswith(head):
            raise truncated_error(self.path, f"only {len(head)} bytes")
        if head != MAGIC:
            raise RecordingError(f"{self.path}: not an MCAP file (starts with {head[:8]!r})")
        self._file.seek(-len(MAGIC), io.SEEK_END)
        if self._file.tell() < len(MAGIC) or self._file.read(len(MAGIC)) != MAGIC:
            raise truncated_error(self.path, "no MCAP footer at the end of the file")
        self._file.seek(0)

    def __enter__(self) -> Recording:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Close the file."""
        self._file.close()

    # -- what is in it ----------------------------------------------------
    @property
    def run_metadata(self) -> dict[str, str]:
        """The ``run`` metadata record (world, planner, seed, versions...), {} if absent."""
        return self.metadata.get(RUN_METADATA, {})

    def counts(self) -> dict[str, int]:
        """Messages per key."""
        stats, channels = self.summary.statistics, self.summary.channels
        if stats is None:
            return {}
        return {channels[c].topic: n for c, n in stats.channel_message_counts.items()}

    def channels(self) -> dict[str, tuple[str, str, str]]:
        """key -> (schema name, schema encoding, message encoding); "" where a channel has none."""
        schemas = self.summary.schemas
        out = {}
        for c in self.summary.channels.values():
            schema = schemas.get(c.schema_id)
            out[c.topic] = (schema.name if schema else "", schema.encoding if schema else "",
                            c.message_encoding)
        return out

    def time_span_ns(self) -> tuple[int, int]:
        """(first, last) log time [ns]; (0, 0) when empty."""
        stats = self.summary.statistics
        if stats is None or stats.message_count == 0:
            return 0, 0
        return stats.message_start_time, stats.message_end_time

    def keys(self, expr: str | Iterable[str] | None = None) -> list[str]:
        """Recorded keys, optionally only those matching key expression(s)."""
        exprs = [expr] if isinstance(expr, str) else expr
        topics = sorted({c.topic for c in self.summary.channels.values()})
        if exprs is None:
            return topics
        return [t for t in topics if any(key_matches(e, t) for e in exprs)]

    # -- iteration --------------------------------------------------------
    def raw(self, keys: str | Iterable[str] | None = None,
            log_time_order: bool = True) -> Iterator[RawMessage]:
        """Stored payloads, in log-time order (default) or file order."""
        topics = None if keys is None else self.keys(keys)
        try:
            for schema, channel, msg in self._reader.iter_messages(
                    topics=topics, log_time_order=log_time_order):
                yield RawMessage(channel.topic, msg.data, msg.log_time, msg.publish_time,
                                 schema.name if schema is not None else "",
                                 channel.message_encoding)
        except Exception as exc:  # the file has its footer (checked on open): damage
            raise RecordingError(
                f"{self.path} is damaged: a chunk fails its CRC or does not decompress "
                f"({exc}); its messages cannot be trusted. Salvage the rest with: "
                f"papf recover {self.path} FIXED.mcap") from None

    def messages(self, keys: str | Iterable[str] | None = None,
                 log_time_order: bool = True) -> Iterator[RecordedMessage]:
        """Decoded messages (raw bytes where the payload is unknown or invalid)."""
        for raw in self.raw(keys, log_time_order):
            yield RecordedMessage(raw.key, decode(raw.schema_name, raw.data), raw.log_time_ns)


def open_recording(path: str | Path) -> Recording:
    """Open ``path`` as a Recording (RecordingError if it is not a complete MCAP)."""
    return Recording(path)


def iter_messages(path: str | Path, keys: str | Iterable[str] | None = None,
                  log_time_order: bool = True) -> Iterator[RecordedMessage]:
    """``for key, msg, log_time_ns in iter_messages("run.mcap"): ...``"""
    with Recording(path) as rec:
        yield from rec.messages(keys, log_time_order)


def read_metadata(path: str | Path) -> dict[str, dict[str, str]]:
    """Every metadata record of a recording: ``{"run": {...}}``."""
    with Recording(path) as rec:
        return rec.metadata
