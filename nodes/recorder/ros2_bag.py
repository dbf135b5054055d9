"""The recorder's ``--format ros2``: a rosbag2 written while the run goes (docs/recording.md).

:class:`Ros2BagWriter` answers what the recorder asks of :class:`~nodes.recorder.writer.RunWriter`
(``write(key, payload, receive_ns)``, ``maybe_flush``, ``close``, ``abandon``, ``stats``),
so the recording loop is the same for both formats. Each sample of ours is decoded and
turned into the ROS 2 face's topics by :class:`common.ros2_bag.BagTopics` — the same
converter as ``papf export ros2``, so a bag recorded live equals an exported one — and
written by rosbags' :class:`~rosbags.rosbag2.Writer` (``metadata.yaml`` + one MCAP, CDR).
Our run metadata (world, planner, seed, versions) goes into the bag's ``custom_data``.

Time: the bag starts at the run's wall-clock time (the first sample's receive time minus
its stamp; :mod:`common.ros2_bag`). What the face does not show (events, statuses, debug
keys of no ROS type) is counted in ``stats.dropped``, not written: the MCAP format keeps
everything, the rosbag2 is for ROS tools. OUT_DIR must not exist (``--force`` replaces a
rosbag2 directory, nothing else). A killed recorder leaves the MCAP without its summary and
no ``metadata.yaml``; ``papf recover OUT_DIR/OUT_DIR.mcap FIXED.mcap`` salvages the messages.
"""

from __future__ import annotations

import shutil
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from rosbags.rosbag2 import StoragePlugin, Writer

from common import ros2_convert as rc
from common.errors import PapfError, RecordingError, SchemaError
from common.ros2_bag import LATCHED, BagTopics
from nodes.recorder.writer import WriterStats, default_metadata, metadata_strings, type_for_key

WALL_MIN_NS = 10**17   # [ns] a stamp past 1973 is wall time already (a real robot's)
FORMATS = ("mcap", "ros2")


def check_bag_dir(path: str | Path, force: bool = False) -> Path:
    """OUT_DIR for a new rosbag2: must not exist; ``force`` replaces a rosbag2 directory
    (one with ``metadata.yaml``) and nothing else. RecordingError, one line, otherwise."""
    p = Path(path)
    if p.suffix == ".mcap":
        raise RecordingError(f"{p}: a rosbag2 is a directory; give OUT_DIR without .mcap "
                             "(or --format mcap for one MCAP file)")
    if p.exists() or p.is_symlink():
        if not force:
            raise RecordingError(f"{p} exists: a rosbag2 is written to a new directory; give "
                                 "another name, or --force to replace it")
        if p.is_symlink() or not p.is_dir() or not (p / "metadata.yaml").is_file():
            raise RecordingError(f"{p} is not a rosbag2 directory (no metadata.yaml): "
                                 "--force replaces only a rosbag2; give another name")
    if not p.parent.is_dir():
        raise RecordingError(f"{p.parent} is not a directory: OUT_DIR's parent must exist")
    return p


class Ros2BagWriter:
    """A rosbag2 of the face's topics being written from our samples (module doc)."""

    def __init__(self, path: str | Path, metadata: Mapping[str, Any] | None = None, *,
                 force: bool = False, **_mcap_options):
        self.path = check_bag_dir(path, force)
        if self.path.exists():
            shutil.rmtree(self.path)
        self.meta = {**default_metadata(), **(metadata or {})}
        ns = str(self.meta.get("namespace") or "rosbot")
        self.topics = BagTopics([ns], _grid(self.meta.get("world")))
        self._bag = Writer(self.path, version=9, storage_plugin=StoragePlugin.MCAP)
        for key, value in metadata_strings(self.meta).items():
            self._bag.set_custom_data(f"papf.{key}", value)
        try:
            self._bag.open()
        except Exception as exc:   # rosbags' own errors: a path it cannot write
            raise RecordingError(f"cannot create rosbag2 {self.path}: {exc}") from None
        self._conns: dict[str, object] = {}
        self._started = False
        self.stats = WriterStats()
        self.closed = False

    def __enter__(self) -> Ros2BagWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def write(self, key: str, data: bytes, receive_ns: int | None = None) -> None:
        """One sample of ours: its ROS 2 messages into the bag (nothing for what the face does
        not show, or a payload that does not decode: counted in ``stats.dropped``)."""
        receive_ns = time.time_ns() if receive_ns is None else receive_ns
        msg_type = type_for_key(key)
        try:
            msg = msg_type.from_bytes(data) if msg_type is not None else None
        except SchemaError:
            msg = None
        stamp = getattr(msg, "stamp_ns", None)
        if stamp is None:
            self.stats.dropped += 1
            return
        if not self._started:
            self._started = True
            self.topics.offset_ns = 0 if stamp >= WALL_MIN_NS else receive_ns - stamp
            self._put(self.topics.static(stamp))
        out = self.topics.convert(key, msg)
        if not out:
            self.stats.dropped += 1
            return
        self._put(out)
        self.stats.bytes += len(data)

    def _put(self, items) -> None:
        for name, typename, msg, stamp_ns in items:
            conn = self._conns.get(name)
            if conn is None:
                conn = self._bag.add_connection(
                    name, typename, typestore=rc.typestore(),
                    offered_qos_profiles=[LATCHED] if name.rsplit("/", 1)[-1] in
                    ("tf_static", "robot_description", "map") else [])
                self._conns[name] = conn
                self.stats.channels += 1
            self._bag.write(conn, stamp_ns, rc.serialize(msg, typename))
            self.stats.messages += 1

    def maybe_flush(self) -> None:
        """Nothing to do: rosbags' MCAP storage writes its chunks as they fill."""

    def close(self) -> None:
        """Write the bag's summary and ``metadata.yaml`` (idempotent)."""
        if not self.closed:
            self.closed = True
            self._bag.close()

    def abandon(self) -> None:
        """Stop writing after an I/O error; keep what is on disk."""
        if not self.closed:
            self.closed = True
            try:
                self._bag.close()
            except Exception:   # noqa: BLE001 - the disk is gone: what is written stays
                pass


def _grid(world):
    """The metadata's world as a map for ``/map`` (None when it names none or does not load)."""
    from worlds.map_world import world_map

    try:
        return world_map(str(world)) if world else None
    except PapfError:
        return None
