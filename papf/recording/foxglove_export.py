"""``papf export foxglove IN.mcap OUT.mcap``: a recording as Foxglove's own channels.

Each recorded message goes, in log-time order, through the viewer's core
(:class:`nodes.viewer.core.ViewCore`) into the viewer's SDK channels
(:class:`nodes.viewer.sink.FoxgloveChannels`) with an MCAP writer as their sink — the very
channels ``papf view`` serves live, JSON-encoded with Foxglove's JSON Schemas. The world
comes from the recording's ``run`` metadata (or ``world=``); the metadata is copied.
Why an export rather than recordings that carry these channels: docs/recording.md.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import foxglove

from common.errors import PapfError, RecordingError
from common.outfiles import check_output, output
from nodes.viewer.core import ViewCore
from nodes.viewer.sink import FoxgloveChannels
from papf.recording.reader import Recording
from schemas.keys import TOPICS
from worlds import World, load_world

REPEAT_NS = 1_000_000_000   # [ns] of log time between repeats of the world and goal


@dataclass
class ExportStats:
    read: int = 0                   # recorded messages read
    skipped: int = 0                # undecodable payloads, keys that are no stack topic
    written: int = 0                # Foxglove messages written
    world: str = ""                 # world drawn ("" = none)
    notes: list[str] = field(default_factory=list)


def stack_topic(key: str) -> str | None:
    """``rosbot/planner/state`` -> ``planner/state`` (longest stack-topic suffix), else None."""
    parts = key.split("/")
    for i in range(1, len(parts)):
        suffix = "/".join(parts[i:])
        if suffix in TOPICS:
            return suffix
    return None


def _world(meta: dict, world: str | World | None, stats: ExportStats) -> World | None:
    if isinstance(world, World):
        return world
    name = world or meta.get("world")
    if not name:
        stats.notes.append("no world in the recording's metadata: obstacles not drawn "
                           "(give --world W)")
        return None
    try:
        return load_world(name)
    except PapfError as exc:
        if world:
            raise
        stats.notes.append(f"world {name!r} of the metadata not found ({exc}); obstacles not "
                           "drawn (give --world W)")
        return None


def export_foxglove(src: str | Path, dst: str | Path, world: str | World | None = None,
                    force: bool = False) -> ExportStats:
    """Write ``dst`` from the recording ``src`` (:func:`common.outfiles.output`: an existing
    ``dst`` only with ``force``, never ``src`` itself); returns the counts."""
    src, dst = Path(src), Path(dst)
    check_output(dst, [src], force)   # before reading anything
    with output(dst, [src], force) as tmp:
        return _export(src, tmp, world)


def _export(src: Path, dst: Path, world) -> ExportStats:
    stats = ExportStats()
    with Recording(src) as rec:
        meta = dict(rec.run_metadata)
        w = _world(meta, world, stats)
        stats.world = w.name if w else ""
        context = foxglove.Context()
        try:
            writer = foxglove.open_mcap(str(dst), allow_overwrite=True, context=context)
        except Exception as exc:
            raise RecordingError(f"cannot write {str(dst)!r}: {exc}") from None
        channels = FoxgloveChannels(context)
        core = ViewCore(w, repeat_ns=REPEAT_NS)
        try:
            for key, msg, _log_time in rec.messages():
                stats.read += 1
                topic = stack_topic(key)
                if topic is None or isinstance(msg, bytes):
                    stats.skipped += 1
                    continue
                before = channels.logged
                channels.log_all(core.on_message(topic, msg))
                stats.written += channels.logged - before
            writer.write_metadata("run", {**meta, "exported_from": str(src),
                                          "exported_by": "papf export foxglove"})
        finally:
            channels.close()
            writer.close()
    return stats
