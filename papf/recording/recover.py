"""Salvage a truncated or damaged recording: ``papf recover BROKEN.mcap FIXED.mcap``.

:func:`recover` copies every intact record (:func:`papf.recording.scan.scan_records`) into a
new, valid file and counts what was lost; the output appears only when complete. Used by
``papf recover``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from mcap.records import Channel, Header, Message, Metadata, Schema
from mcap.writer import Writer

import papf
from common.errors import RecordingError
from common.outfiles import OutputError, check_output, output
from nodes.recorder.writer import COMPRESSIONS
from papf.recording.scan import ScanStats, open_regular, scan_records


@dataclass
class RecoverStats:
    """What :func:`recover` kept and lost. Times in integer nanoseconds."""

    messages: int = 0
    channels: int = 0
    schemas: int = 0
    metadata: int = 0
    orphan_messages: int = 0   # messages whose channel record was lost
    first_log_ns: int | None = None
    last_log_ns: int | None = None
    first_receive_ns: int | None = None
    last_receive_ns: int | None = None
    scan: ScanStats = field(default_factory=ScanStats)

    @property
    def skipped_chunks(self) -> int:
        """Chunks that failed their CRC or did not decompress."""
        return self.scan.bad_chunks

    @property
    def complete(self) -> bool:
        """The source had its data-end record and nothing in it was damaged."""
        return self.scan.data_end and not self.scan.damaged

    @property
    def lost_messages(self) -> int | None:
        """Messages lost: what the file's own statistics say it held minus what was kept,
        else the message indexes of the damaged chunks; None when nothing tells."""
        if self.scan.expected_messages is not None:
            return max(0, self.scan.expected_messages - self.messages)
        if self.scan.data_end and (self.scan.lost_messages or not self.scan.damaged):
            return self.scan.lost_messages + self.orphan_messages
        return None

    @property
    def stopped_at(self) -> str:
        """Where the scan stopped (``end of file``, or what it met at which byte)."""
        return self.scan.stopped_at

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

    def lost(self) -> str:
        """What was lost, in words ('' when nothing)."""
        sc, parts = self.scan, []
        if sc.bad_chunks:
            parts.append(f"{sc.bad_chunks} damaged chunk(s) failed their CRC, did not "
                         "decompress or claimed more than the size bound")
        if sc.damaged_bytes:
            parts.append(f"{sc.damaged_bytes} damaged bytes skipped at byte(s) "
                         + ", ".join(map(str, sc.damage_at)))
        if self.orphan_messages:
            parts.append(f"{self.orphan_messages} messages lost their channel")
        cut = "" if sc.data_end else (f"the file was cut short ({sc.stopped_at}): whatever "
                                      "was recorded after that is lost")
        if not parts:
            return cut
        n = self.lost_messages
        head = f"LOST {n} messages" if n is not None else "LOST an unknown number of messages"
        return f"{head}: " + "; ".join(parts + ([cut] if cut else []))

    def summary(self) -> str:
        """One line of what was kept and what was lost."""
        total = f" of {self.scan.expected_messages}" if self.scan.expected_messages is not None \
            else ""
        text = (f"kept {self.messages}{total} messages on {self.channels} channels, "
                f"log time span {self.log_span_s:.3f} s, received over "
                f"{self.receive_span_s:.3f} s")
        lost = self.lost()
        return f"{text}; {lost}" if lost else f"{text}; the file was complete, nothing lost"

    def to_json(self, output: str) -> dict:
        """The outcome as ``papf recover --json`` prints it."""
        sc = self.scan
        return {"output": output, "messages": self.messages, "log_span_s": self.log_span_s,
                "receive_span_s": self.receive_span_s, "channels": self.channels,
                "complete": self.complete, "skipped_chunks": sc.bad_chunks,
                "lost_messages": self.lost_messages, "expected_messages": sc.expected_messages,
                "damaged_bytes": sc.damaged_bytes, "damage_at": sc.damage_at,
                "truncated": not sc.data_end, "stopped_at": sc.stopped_at}


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


def recover(broken: str | Path, fixed: str | Path, compression: str = "zstd",
            force: bool = False) -> RecoverStats:
    """Write every intact message of ``broken`` into a new, valid MCAP ``fixed``
    (:func:`common.outfiles.output`: an existing ``fixed`` only with ``force``, never ``broken``).

    A recorder killed mid-run leaves an MCAP without its summary and footer, often with
    a half-written last record; a copy or a disk may flip bytes anywhere. :func:`recover`
    walks the records with :func:`papf.recording.scan.scan_records` (framing checked
    against the file size, every chunk decompressed and CRC-checked, resynchronising on
    the next intact chunk after damage) and re-writes every intact schema, channel,
    metadata record and message into a new, valid file (with indexes). What was lost is
    counted — damaged chunks, the messages they held, skipped bytes — and said.

    The output is written beside its final name and renamed into place only when
    complete: a full disk or a missing directory leaves no partial or empty file behind.
    """
    broken, fixed = Path(broken), Path(fixed)
    try:
        check_output(fixed, [broken], force)
    except OutputError as exc:
        raise RecordingError(str(exc)) from None
    stats = RecoverStats()
    with open_regular(broken) as src:
        try:
            with output(fixed, [broken], force) as tmp, open(tmp, "wb") as out:
                _copy_all(src, out, stats, compression)
        except OSError as exc:
            raise RecordingError(f"cannot write {fixed}: {exc.strerror or exc}; nothing was "
                                 "written (free some space, or recover elsewhere)") from None
    return stats


def _copy_all(src, out, stats: RecoverStats, compression: str) -> None:
    writer = Writer(out, compression=COMPRESSIONS[compression])
    copier = _Copier(writer, stats)
    started = False
    for rec in scan_records(src, stats.scan):
        if isinstance(rec, Header) and not started:
            writer.start(profile=rec.profile, library=f"papf-stack/{papf.__version__}")
            started = True
            continue
        if not started:
            writer.start(library=f"papf-stack/{papf.__version__}")
            started = True
        copier.record(rec)
    if not started:
        writer.start(library=f"papf-stack/{papf.__version__}")
    writer.finish()
