"""Salvage a truncated or damaged recording: ``papf recover BROKEN.mcap FIXED.mcap``.

A recorder killed mid-run leaves an MCAP without its summary and footer, often with
a half-written last record. :func:`recover` reads the records sequentially, checking
each record's framing against the file size (a cut record is never half-read),
decompresses and CRC-checks every chunk, and re-writes every complete schema,
channel, metadata record and message into a new, valid file (with indexes). It stops
at the first incomplete record; a chunk that fails its CRC or does not decompress is
skipped and counted.
"""

from __future__ import annotations

import io
import struct
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from mcap.data_stream import ReadDataStream
from mcap.opcode import Opcode
from mcap.records import Channel, Chunk, Header, Message, Metadata, Schema
from mcap.stream_reader import breakup_chunk
from mcap.writer import Writer

import papf
from common.errors import RecordingError
from nodes.recorder.writer import COMPRESSIONS
from papf.recording.reader import MAGIC

_FRAME = struct.Struct("<BQ")  # record opcode, record length [bytes]


@dataclass
class RecoverStats:
    """What :func:`recover` kept. Times in integer nanoseconds."""

    messages: int = 0
    channels: int = 0
    schemas: int = 0
    metadata: int = 0
    skipped_chunks: int = 0    # chunks that failed their CRC or did not decompress
    orphan_messages: int = 0   # messages whose channel record was lost
    first_log_ns: int | None = None
    last_log_ns: int | None = None
    first_receive_ns: int | None = None
    last_receive_ns: int | None = None
    bytes_read: int = 0        # bytes of the broken file made of complete records
    bytes_total: int = 0
    complete: bool = False     # the source already had its data-end record
    stopped_at: str = ""       # why reading stopped

    @property
    def log_span_s(self) -> float:
        """Span of the kept messages' log times (sim time) [s]."""
        if self.first_log_ns is None:
            return 0.0
        return (self.last_log_ns - self.first_log_ns) / 1e9

    @property
    def receive_span_s(self) -> float:
        """Wall-clock span over which the kept messages were received [s]."""
        if self.first_receive_ns is None:
            return 0.0
        return (self.last_receive_ns - self.first_receive_ns) / 1e9

    def summary(self) -> str:
        return (f"kept {self.messages} messages on {self.channels} channels, "
                f"log time span {self.log_span_s:.3f} s, received over "
                f"{self.receive_span_s:.3f} s; read {self.bytes_read} of "
                f"{self.bytes_total} bytes ({self.stopped_at})")


def _frames(f: io.BufferedReader, size: int, stats: RecoverStats) -> Iterator[tuple[int, bytes]]:
    """Complete records ``(opcode, body)`` after the leading magic."""
    pos = len(MAGIC)
    while True:
        if pos + _FRAME.size > size:
            stats.stopped_at = "end of file" if pos == size else f"cut record header at byte {pos}"
            return
        opcode, length = _FRAME.unpack(f.read(_FRAME.size))
        if pos + _FRAME.size + length > size:
            stats.stopped_at = f"cut record (opcode {opcode:#04x}) at byte {pos}"
            return
        body = f.read(length)
        pos += _FRAME.size + length
        stats.bytes_read = pos
        yield opcode, body


class _Copier:
    """Re-registers schemas and channels under the writer's new ids, copies messages."""

    def __init__(self, writer: Writer, stats: RecoverStats):
        self.writer, self.stats = writer, stats
        self.schema_ids: dict[int, int] = {0: 0}
        self.channel_ids: dict[int, int] = {}

    def record(self, rec: object) -> None:
        if isinstance(rec, Message):
            self.message(rec)
        elif isinstance(rec, Schema) and rec.id not in self.schema_ids:
            self.schema_ids[rec.id] = self.writer.register_schema(rec.name, rec.encoding, rec.data)
            self.stats.schemas += 1
        elif isinstance(rec, Channel) and rec.id not in self.channel_ids:
            schema = self.schema_ids.get(rec.schema_id, 0)  # lost schema: keep data, no schema
            self.channel_ids[rec.id] = self.writer.register_channel(
                rec.topic, rec.message_encoding, schema, dict(rec.metadata))
            self.stats.channels += 1
        elif isinstance(rec, Metadata):
            self.writer.add_metadata(rec.name, dict(rec.metadata))
            self.stats.metadata += 1

    def message(self, msg: Message) -> None:
        channel = self.channel_ids.get(msg.channel_id)
        if channel is None:
            self.stats.orphan_messages += 1
            return
        self.writer.add_message(channel, msg.log_time, msg.data, msg.publish_time, msg.sequence)
        s = self.stats
        s.messages += 1
        s.first_log_ns = msg.log_time if s.first_log_ns is None else min(s.first_log_ns, msg.log_time)
        s.last_log_ns = msg.log_time if s.last_log_ns is None else max(s.last_log_ns, msg.log_time)
        t = msg.publish_time
        s.first_receive_ns = t if s.first_receive_ns is None else min(s.first_receive_ns, t)
        s.last_receive_ns = t if s.last_receive_ns is None else max(s.last_receive_ns, t)


def _parse(opcode: int, body: bytes):
    stream = ReadDataStream(io.BytesIO(body))
    if opcode == Opcode.MESSAGE:
        return Message.read(stream, len(body))
    reader = {Opcode.SCHEMA: Schema.read, Opcode.CHANNEL: Channel.read,
              Opcode.METADATA: Metadata.read, Opcode.CHUNK: Chunk.read,
              Opcode.HEADER: Header.read}.get(opcode)
    return reader(stream) if reader is not None else None  # indexes etc.: rebuilt by the writer


def recover(broken: str | Path, fixed: str | Path, compression: str = "zstd") -> RecoverStats:
    """Write every complete message of ``broken`` into a new, valid MCAP ``fixed``."""
    broken, fixed = Path(broken), Path(fixed)
    if broken.resolve() == fixed.resolve():
        raise RecordingError(f"recover would overwrite its input {broken}; name another output")
    try:
        src = open(broken, "rb")
    except OSError as exc:
        raise RecordingError(f"cannot open recording {str(broken)!r}: {exc}") from None
    with src:
        size = src.seek(0, io.SEEK_END)
        src.seek(0)
        head = src.read(len(MAGIC))
        if head != MAGIC:
            what = (f"has only {size} bytes" if MAGIC.startswith(head)
                    else "does not start with the MCAP magic")
            raise RecordingError(f"{broken}: {what}; there is nothing to recover")
        stats = RecoverStats(bytes_total=size, bytes_read=len(MAGIC))
        with open(fixed, "wb") as out:
            writer = Writer(out, compression=COMPRESSIONS[compression])
            copier = _Copier(writer, stats)
            started = False
            for opcode, body in _frames(src, size, stats):
                if opcode == Opcode.DATA_END:
                    stats.complete, stats.stopped_at = True, "data end: the file was complete"
                    break
                try:
                    rec = _parse(opcode, body)
                except Exception as exc:  # a record with intact framing but bad content
                    stats.stopped_at = f"unreadable record (opcode {opcode:#04x}): {exc}"
                    break
                if isinstance(rec, Header) and not started:
                    writer.start(profile=rec.profile, library=f"papf-stack/{papf.__version__}")
                    started = True
                    continue
                if not started:
                    writer.start(library=f"papf-stack/{papf.__version__}")
                    started = True
                _copy(copier, rec, stats)
            if not started:
                writer.start(library=f"papf-stack/{papf.__version__}")
            writer.finish()
    return stats


def _copy(copier: _Copier, rec: object, stats: RecoverStats) -> None:
    if not isinstance(rec, Chunk):
        copier.record(rec)
        return
    try:
        records = breakup_chunk(rec, validate_crc=True)
    except Exception:  # CRC mismatch, bad compression: this chunk is lost
        stats.skipped_chunks += 1
        return
    for inner in records:
        copier.record(inner)
