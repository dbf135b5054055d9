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

from rosbags.interfaces import (
    Qos,
    QosDurability,
    QosHistory,
    QosLiveliness,
    QosReliability,
    QosTime,
)
from rosbags.rosbag2 import StoragePlugin, Writer

from common import ros2_convert as rc
from common.errors import RecordingError
from common.urdf import rosbot_urdf
from papf.recording.foxglove_export import stack_topic
from papf.recording.reader import Recording
from schemas.messages import BatteryState, Odometry, PlannerState, Scan, Twist

_NEVER = QosTime(sec=0, nsec=0)
LATCHED = Qos(history=QosHistory.KEEP_LAST, depth=1, reliability=QosReliability.RELIABLE,
              durability=QosDurability.TRANSIENT_LOCAL, deadline=_NEVER, lifespan=_NEVER,
              liveliness=QosLiveliness.AUTOMATIC, liveliness_lease_duration=_NEVER,
              avoid_ros_namespace_conventions=False)
TOPIC_TYPES = {"scan": rc.LASER_SCAN, "odom": rc.ODOMETRY, "tf": rc.TF_MESSAGE,
               "tf_static": rc.TF_MESSAGE, "robot_description": rc.STRING, "cmd_vel": rc.TWIST,
               "battery": rc.BATTERY_STATE, "plan": rc.PATH, "markers": rc.MARKER_ARRAY}
LATCHED_TOPICS = ("tf_static", "robot_description")


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


class _Robot:
    """One namespace's topic names, frames and latest pose."""

    def __init__(self, ns: str, several: bool):
        self.prefix = f"/{ns}" if several else ""
        self.frame_prefix = f"{ns}/" if several else ""
        self.xy: tuple[float, float] | None = None

    def topic(self, name: str) -> str:
        return f"{self.prefix}/{name}"

    def frames(self, msg):
        """``msg`` with base_link / laser renamed to this robot's frames (several robots)."""
        if not self.frame_prefix:
            return msg
        for holder in _frame_holders(msg):
            for attr in ("frame_id", "child_frame_id"):
                value = getattr(holder, attr, None)
                if value in ("base_link", "laser"):
                    setattr(holder, attr, self.frame_prefix + value)
        return msg


def _frame_holders(msg) -> list:
    out = [msg]
    if hasattr(msg, "header"):
        out.append(msg.header)
    for tf in getattr(msg, "transforms", ()):
        out += [tf, tf.header]
    return out


def _convert(robot: _Robot, topic: str, msg) -> list[tuple[str, object]]:
    """(face topic name, ROS 2 message) for one recorded message of ours."""
    if topic == "scan" and isinstance(msg, Scan):
        return [("scan", rc.laser_scan(msg))]
    if topic == "odom" and isinstance(msg, Odometry):
        robot.xy = (msg.x, msg.y)
        return [("odom", rc.odometry(msg)), ("tf", rc.tf_odom(msg))]
    if topic == "cmd_vel" and isinstance(msg, Twist):
        return [("cmd_vel", rc.twist(msg))]
    if topic == "battery" and isinstance(msg, BatteryState):
        return [("battery", rc.battery_state(msg))]
    if topic == "planner/state" and isinstance(msg, PlannerState):
        return [("plan", rc.path(msg)), ("markers", rc.markers(msg, robot.xy))]
    return []


def _namespaces(rec: Recording) -> list[str]:
    found = []
    for key in rec.keys():
        topic = stack_topic(key)
        if topic is not None:
            found.append(key[: -len(topic) - 1])
    return sorted(set(found))


def export_ros2(src: str | Path, dst: str | Path) -> Ros2ExportStats:
    """Write the rosbag2 directory ``dst`` (must not exist) from the recording ``src``.

    OUT_DIR is a rosbag2 directory (``metadata.yaml`` + one MCAP with ``ros2msg`` schemas and
    ``cdr`` messages) written by rosbags' :class:`~rosbags.rosbag2.Writer`, of the topics the
    stack's ROS 2 face publishes (conversions: :mod:`common.ros2_convert`):

    ===================== ================================ =====================================
    topic                 type                             from
    ===================== ================================ =====================================
    /scan                 sensor_msgs/msg/LaserScan        ``scan``
    /odom, /tf            nav_msgs/msg/Odometry,           ``odom`` (``/tf``: odom -> base_link)
                          tf2_msgs/msg/TFMessage
    /tf_static            tf2_msgs/msg/TFMessage           base_link -> laser (common.robot), once
    /robot_description    std_msgs/msg/String              the URDF (common.urdf), once
    /cmd_vel              geometry_msgs/msg/Twist          ``cmd_vel``
    /battery              sensor_msgs/msg/BatteryState     ``battery`` (the meter's figures)
    /plan, /markers       nav_msgs/msg/Path,               ``planner/state`` (the prediction;
                          visualization_msgs/msg/MarkerArray  the planner's mind)
    ===================== ================================ =====================================

    ``/tf_static`` and ``/robot_description`` are offered transient-local, as ROS 2 publishes
    them. Bag time and header stamps are the recording's stamps: sim time from 0 in sim runs.
    With several robots (namespaces) the topics are ``/<robot>/scan``… and the robot's frames
    ``<robot>/base_link``, ``<robot>/laser`` (``odom`` is the world frame all share).
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
        robots = {ns: _Robot(ns, len(namespaces) > 1) for ns in namespaces}
        work = Path(tempfile.mkdtemp(prefix=f".{dst.name}.partial-", dir=dst.parent))
        try:
            _write(rec, robots, work / dst.name, stats)
            check_out_dir(src, dst)   # made meanwhile by someone else: still never overwrite
            (work / dst.name).rename(dst)
        finally:
            shutil.rmtree(work, ignore_errors=True)
    return stats


def _write(rec: Recording, robots: dict[str, _Robot], bag: Path, stats: Ros2ExportStats) -> None:
    first_ns = max(rec.time_span_ns()[0], 0)
    with Writer(bag, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        conns = {}
        for ns, robot in robots.items():
            for name, msgtype in TOPIC_TYPES.items():
                qos = [LATCHED] if name in LATCHED_TOPICS else []
                conns[(ns, name)] = writer.add_connection(
                    robot.topic(name), msgtype, typestore=rc.typestore(),
                    offered_qos_profiles=qos)

        def put(ns: str, name: str, msg, stamp_ns: int) -> None:
            data = rc.serialize(robots[ns].frames(msg), TOPIC_TYPES[name])
            writer.write(conns[(ns, name)], stamp_ns, data)
            stats.written[robots[ns].topic(name)] += 1

        for ns in robots:
            put(ns, "robot_description", rc.string(rosbot_urdf()), first_ns)
            put(ns, "tf_static", rc.tf_static(first_ns), first_ns)
        for key, msg, log_ns in rec.messages():
            stats.read += 1
            topic = stack_topic(key)
            ns = key[: -len(topic) - 1] if topic else None
            out = _convert(robots[ns], topic, msg) if ns in robots else []
            stats.skipped += not out
            for name, ros_msg in out:
                put(ns, name, ros_msg, getattr(msg, "stamp_ns", log_ns))
