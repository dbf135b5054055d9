"""``papf export ros2 IN.mcap OUT_DIR``: a recording as a rosbag2 that ROS 2 tools play.

:func:`export_ros2` writes a rosbag2 directory (``metadata.yaml`` + one MCAP, CDR) of the
topics the stack's ROS 2 face publishes (conversions: :mod:`common.ros2_convert`); OUT_DIR
is never overwritten. Used by ``papf export ros2``.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

from rosbags.rosbag2 import StoragePlugin, Writer

from common import ros2_convert as rc
from common.errors import PapfError, RecordingError
from common.ros2_bag import LATCHED, BagTopics, split_key
from papf.recording.reader import Recording

WALL_MIN_NS = 10**17   # [ns] a stamp past 1973 is already wall time (a robot's): no shift


@dataclass
class Ros2ExportStats:
    read: int = 0                                        # recorded messages read
    written: Counter = field(default_factory=Counter)    # ROS 2 topic -> messages
    skipped: int = 0                                     # not a face topic, or undecodable
    namespaces: tuple[str, ...] = ()


def check_out_dir(src: Path, dst: Path) -> None:
    """OUT_DIR must not exist (never overwritten), and cannot be the input."""
    if dst.exists():
        same = src.exists() and os.path.samefile(src, dst)
        raise RecordingError(f"{dst} {'is the input' if same else 'exists'}: the export "
                             "writes a new rosbag2 directory and never overwrites; give a "
                             "new OUT_DIR")
    if not dst.parent.is_dir():
        raise RecordingError(f"{dst.parent} is not a directory: OUT_DIR's parent must exist")


def _namespaces(rec: Recording) -> list[str]:
    return sorted({split[0] for key in rec.keys() if (split := split_key(key)) is not None})


def wall_offset(rec: Recording) -> int:
    """[ns] to add to the recording's stamps to put them on the wall clock: the first
    message's receive time minus its stamp (0 when stamps are already wall time)."""
    for raw in rec.raw():
        return 0 if raw.log_time_ns >= WALL_MIN_NS else raw.publish_time_ns - raw.log_time_ns
    return 0


def world_grid(rec: Recording):
    """The recording's world as a map (:func:`worlds.map_world.world_map`), or None
    when the metadata names none or it does not load."""
    from worlds.map_world import world_map

    try:
        return world_map(rec.run_metadata.get("world") or None)
    except PapfError:
        return None


def export_ros2(src: str | Path, dst: str | Path) -> Ros2ExportStats:
    """Write the rosbag2 directory ``dst`` (must not exist) from the recording ``src``.

    OUT_DIR is a rosbag2 directory (``metadata.yaml`` + one MCAP with ``ros2msg`` schemas and
    ``cdr`` messages) written by rosbags' :class:`~rosbags.rosbag2.Writer`, of the topics the
    stack's ROS 2 face publishes (conversions: :mod:`common.ros2_convert`):

    ===================== ================================ =====================================
    topic                 type                             from
    ===================== ================================ =====================================
    /scan                 sensor_msgs/msg/LaserScan        ``scan``
    /odom, /tf            nav_msgs/msg/Odometry,           ``odom`` (``/tf``: odom -> base_link;
                          tf2_msgs/msg/TFMessage           map -> odom with a map)
    /joint_states, /tf    sensor_msgs/msg/JointState       ``wheels`` (angles integrated; the
                                                           wheels' transforms)
    /clock                rosgraph_msgs/msg/Clock          ``clock`` (sim runs)
    /tf_static            tf2_msgs/msg/TFMessage           base_link -> laser (common.robot), once
    /robot_description    std_msgs/msg/String              the URDF (common.urdf), once
    /map                  nav_msgs/msg/OccupancyGrid       the metadata's world, once
    /cmd_vel              geometry_msgs/msg/Twist          ``cmd_vel``
    /battery              sensor_msgs/msg/BatteryState     ``battery`` (the meter's figures)
    /plan, /markers       nav_msgs/msg/Path,               ``planner/state`` (the prediction;
                          visualization_msgs/msg/MarkerArray  the planner's mind)
    ===================== ================================ =====================================

    ``/tf_static``, ``/robot_description`` and ``/map`` are offered transient-local, as ROS 2
    publishes them. Time: the bag starts at the wall-clock time its run started; bag time,
    header stamps and ``/clock`` are the run's stamps shifted by that one offset
    (:mod:`common.ros2_bag`: sim time stays consistent for ``ros2 bag play --clock``). With
    several robots (namespaces) the topics are ``/<robot>/scan``… and the robot's frames
    ``<robot>/base_link``, ``<robot>/laser`` (``odom`` and ``map`` are the world frames all
    share).
    OUT_DIR is never overwritten: the bag is written beside it under a temporary name and
    renamed at the end, so an interrupted export leaves no half bag under OUT_DIR.
    """
    src, dst = Path(src), Path(dst)
    check_out_dir(src, dst)
    stats = Ros2ExportStats()
    with Recording(src) as rec:
        namespaces = _namespaces(rec)
        if not namespaces:
            raise RecordingError(f"{src}: no stack topics (scan, odom, …) to export; is this a "
                                 "papf run recording?")
        stats.namespaces = tuple(namespaces)
        topics = BagTopics(namespaces, world_grid(rec), wall_offset(rec))
        work = Path(tempfile.mkdtemp(prefix=f".{dst.name}.partial-", dir=dst.parent))
        try:
            _write(rec, topics, work / dst.name, stats)
            check_out_dir(src, dst)   # made meanwhile by someone else: still never overwrite
            (work / dst.name).rename(dst)
        finally:
            shutil.rmtree(work, ignore_errors=True)
    return stats


def _write(rec: Recording, topics: BagTopics, bag: Path, stats: Ros2ExportStats) -> None:
    first_ns = max(rec.time_span_ns()[0], 0)
    with Writer(bag, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        for key, value in rec.run_metadata.items():   # world, planner, seed … for papf report
            writer.set_custom_data(f"papf.{key}", str(value))
        latched = {name for name, _t, is_latched in topics.connections() if is_latched}
        conns: dict = {}

        def put(items) -> None:
            for name, typename, msg, stamp_ns in items:
                if name not in conns:   # a topic appears once it has a message
                    conns[name] = writer.add_connection(
                        name, typename, typestore=rc.typestore(),
                        offered_qos_profiles=[LATCHED] if name in latched else [])
                writer.write(conns[name], stamp_ns, rc.serialize(msg, typename))
                stats.written[name] += 1

        put(topics.static(first_ns))
        for key, msg, _log_ns in rec.messages():
            stats.read += 1
            out = topics.convert(key, msg)
            stats.skipped += not out
            put(out)
