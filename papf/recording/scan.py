"""Walk an MCAP file record by record, trusting nothing: framing, chunk CRCs, resync.

:func:`scan_records` yields every intact record; damage is counted in :class:`ScanStats`,
never raised. Used by ``papf recover`` (copy what is intact) and ``papf info`` (say what
is damaged).
"""

from __future__ import annotations

import io
import mmap
import os
import stat
import struct
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

from mcap.data_stream import ReadDataStream
from mcap.opcode import Opcode
from mcap.records import (
    Attachment,
    AttachmentIndex,
    Channel,
    Chunk,
    ChunkIndex,
    DataEnd,
    Footer,
    Header,
    Message,
    MessageIndex,
    Metadata,
    MetadataIndex,
    Schema,
    Statistics,
    SummaryOffset,
)
from mcap.stream_reader import breakup_chunk

from common.errors import RecordingError
from papf.recording.bounds import check_chunk

MAGIC = b"\x89MCAP0\r\n"
FRAME = struct.Struct("<BQ")       # record opcode, record length [bytes]
COMPRESSIONS = ("", "zstd", "lz4")
MIN_CHUNK_BODY = 8 + 8 + 8 + 4 + 4 + 8   # [bytes] a chunk's fixed fields
_READERS = {
    Opcode.ATTACHMENT: Attachment.read, Opcode.ATTACHMENT_INDEX: AttachmentIndex.read,
    Opcode.CHANNEL: Channel.read, Opcode.CHUNK: Chunk.read, Opcode.CHUNK_INDEX: ChunkIndex.read,
    Opcode.DATA_END: DataEnd.read, Opcode.FOOTER: Footer.read, Opcode.HEADER: Header.read,
    Opcode.MESSAGE_INDEX: MessageIndex.read, Opcode.METADATA: Metadata.read,
    Opcode.METADATA_INDEX: MetadataIndex.read, Opcode.SCHEMA: Schema.read,
    Opcode.STATISTICS: Statistics.read, Opcode.SUMMARY_OFFSET: SummaryOffset.read,
}


@dataclass
class ScanStats:
    """What a scan found. Offsets and sizes in bytes."""

    bytes_total: int = 0
    bytes_read: int = 0              # end of the last intact record
    chunks: int = 0                  # intact chunks
    bad_chunks: int = 0              # chunks that failed their CRC or did not decompress
    lost_messages: int = 0           # messages of bad chunks (from their message indexes)
    damaged_bytes: int = 0           # bytes skipped to resynchronise
    damage_at: list[int] = field(default_factory=list)   # offsets of damage (first 10)
    data_end: bool = False           # the data-end record was reached
    expected_messages: int | None = None   # from the summary's statistics, when readable
    stopped_at: str = ""

    @property
    def damaged(self) -> bool:
        """Whether the scan met bad chunks or damaged bytes."""
        return bool(self.bad_chunks or self.damaged_bytes)

    def note_damage(self, pos: int) -> None:
        """Note damage at byte ``pos`` (the first ten kept)."""
        if len(self.damage_at) < 10:
            self.damage_at.append(pos)


def open_regular(path: str | Path, what: str = "recording"):
    """Open a regular file for reading; a FIFO, device or directory is refused (a FIFO
    would block forever)."""
    try:
        st = os.stat(path)
    except OSError as exc:
        raise RecordingError(f"cannot open {what} {str(path)!r}: {exc.strerror}") from None
    if not stat.S_ISREG(st.st_mode):
        raise RecordingError(f"{what} {str(path)!r} is not a regular file (a FIFO, device or "
                             "directory); give an .mcap file")
    try:
        return open(path, "rb")
    except OSError as exc:
        raise RecordingError(f"cannot open {what} {str(path)!r}: {exc.strerror}") from None


def _parse(opcode: int, body: bytes | memoryview):
    """The record, or raise (any exception: the content is damaged)."""
    stream = ReadDataStream(io.BytesIO(body))
    if opcode == Opcode.MESSAGE:
        return Message.read(stream, len(body))
    rec = _READERS[opcode](stream)
    if stream.count != len(body) and opcode != Opcode.CHUNK:
        raise ValueError(f"record of {len(body)} bytes parsed as {stream.count}")
    if isinstance(rec, Chunk) and (rec.compression not in COMPRESSIONS
                                   or stream.count != len(body)):
        raise ValueError("inconsistent chunk fields")
    return rec


def _chunk_at(mm, pos: int, size: int) -> Chunk | None:
    """A chunk record at ``pos`` that parses and passes its CRC, or None."""
    if pos + FRAME.size > size or mm[pos] != Opcode.CHUNK:
        return None
    _, length = FRAME.unpack_from(mm, pos)
    if length < MIN_CHUNK_BODY or pos + FRAME.size + length > size:
        return None
    try:
        chunk = _parse(Opcode.CHUNK, mm[pos + FRAME.size:pos + FRAME.size + length])
        check_chunk(chunk, "chunk")
        breakup_chunk(chunk, validate_crc=True)
    except Exception:
        return None
    return chunk


def next_chunk(mm, start: int, size: int) -> int | None:
    """Offset of the next intact chunk at or after ``start``, or None."""
    pos = start
    while True:
        pos = mm.find(bytes([Opcode.CHUNK]), pos, size)
        if pos < 0:
            return None
        if _chunk_at(mm, pos, size) is not None:
            return pos
        pos += 1


def _read_at(mm, pos: int, size: int):
    """(opcode, record, end) of an intact record at ``pos``; (opcode, None, why) if damaged."""
    if pos + FRAME.size > size:
        return None, None, "cut record header"
    opcode, length = FRAME.unpack_from(mm, pos)
    if opcode not in _READERS and opcode != Opcode.MESSAGE:
        return opcode, None, f"unknown record opcode {opcode:#04x}"
    end = pos + FRAME.size + length
    if end > size:
        return opcode, None, f"record (opcode {opcode:#04x}) longer than the file"
    try:
        return opcode, _parse(opcode, mm[pos + FRAME.size:end]), end
    except Exception as exc:
        return opcode, None, f"unreadable record (opcode {opcode:#04x}): {exc}"


def scan_records(f, stats: ScanStats) -> Iterator[object]:
    """Intact records of the data section of the open file ``f``.

    :func:`scan_records` yields every record of the data section that is intact — the
    records inside a chunk only when the chunk decompresses and passes its CRC. Damage is
    counted in :class:`ScanStats`, never raised:

    - a record whose opcode is unknown, whose length runs past the end of the file, or
      whose content does not parse is *damage*: the scan resynchronises on the next chunk
      that parses and passes its CRC (a cut record at the very end is a truncation);
    - a chunk that fails its CRC or does not decompress is skipped; the message index
      records that follow it say how many messages it held (``lost_messages``);
    - after the data-end record, the summary's statistics (when readable) give the number
      of messages the file should hold (``expected_messages``).

    Used by ``papf recover`` (copy what is intact) and ``papf info`` (say what is damaged).
    """
    size = os.fstat(f.fileno()).st_size
    stats.bytes_total = size
    head = f.read(len(MAGIC))
    if head != MAGIC:
        what = (f"has only {size} bytes" if MAGIC.startswith(head)
                else "does not start with the MCAP magic")
        raise RecordingError(f"{getattr(f, 'name', 'file')}: {what}; there is nothing to recover")
    stats.bytes_read = pos = len(MAGIC)
    if size == pos:
        stats.stopped_at = "end of file"
        return
    with mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as mm:
        counting_lost = False
        while pos < size:
            opcode, rec, end = _read_at(mm, pos, size)
            if rec is None:
                nxt = next_chunk(mm, pos + 1, size)
                if nxt is None:
                    stats.stopped_at = f"{end} at byte {pos}" + (
                        "" if opcode is None or "longer" in end else "; no intact chunk after it")
                    if "longer" not in end and opcode is not None:
                        stats.note_damage(pos)
                        stats.damaged_bytes += size - pos
                    return
                stats.note_damage(pos)
                stats.damaged_bytes += nxt - pos
                pos = nxt
                continue
            pos = stats.bytes_read = end
            if isinstance(rec, Chunk):
                counting_lost = False
                try:
                    check_chunk(rec, "chunk")   # a decompression bomb: skipped as damage
                    inner = breakup_chunk(rec, validate_crc=True)
                except Exception:
                    stats.bad_chunks += 1
                    stats.note_damage(pos)
                    counting_lost = True
                    continue
                stats.chunks += 1
                yield from inner
            elif isinstance(rec, MessageIndex):
                if counting_lost:
                    stats.lost_messages += len(rec.records)
            elif isinstance(rec, DataEnd):
                stats.data_end = True
                stats.stopped_at = "data end"
                _read_summary(mm, pos, size, stats)
                return
            else:
                counting_lost = False
                yield rec
        stats.stopped_at = "end of file"


def _read_summary(mm, pos: int, size: int, stats: ScanStats) -> None:
    """The statistics of the summary section after data end, best effort."""
    while pos < size:
        opcode, rec, end = _read_at(mm, pos, size)
        if rec is None or isinstance(rec, Footer):
            return
        if isinstance(rec, Statistics):
            stats.expected_messages = rec.message_count
            return
        pos = end


def scan_file(path: str | Path) -> tuple[ScanStats, int]:
    """(what a full scan of ``path`` finds, the number of intact messages).

    A message counts as intact as ``papf recover`` would keep it: readable, and on a channel
    whose record came before it (a message whose channel record was lost cannot be read,
    so ``info`` and ``recover`` report the same loss)."""
    stats = ScanStats()
    channels: set[int] = set()
    n = 0
    with open_regular(path) as f:
        for rec in scan_records(f, stats):
            if isinstance(rec, Channel):
                channels.add(rec.id)
            elif isinstance(rec, Message) and rec.channel_id in channels:
                n += 1
    return stats, n
