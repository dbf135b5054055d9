"""ROS 2 messages without ROS: build, encode and decode them as CDR (docs/architecture.md "The robot").

``zenoh-bridge-ros2dds`` carries each ROS 2 topic as a Zenoh key whose payload is the
message in CDR with its 4-byte encapsulation header (``00 01 00 00`` = CDR, little
endian). ``rosbags`` (``get_typestore(Stores.ROS2_HUMBLE)``, ``serialize_cdr`` /
``deserialize_cdr``) reads and writes exactly that, so the robot side needs no ROS
install here. This module holds the typestore, the message builders the driver, the
LiDAR source and the emulator share, and the time/quaternion conversions.

Frames follow REP 103/105: ``odom`` (world-fixed) -> ``base_link`` (x forward, z up);
yaw is the rotation about z, CCW positive.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
from rosbags.typesys import Stores, get_typestore

from common.errors import SchemaError
from common.units import NS_PER_S as NS

TWIST = "geometry_msgs/msg/Twist"
TWIST_STAMPED = "geometry_msgs/msg/TwistStamped"   # Jazzy's diff-drive controller can take it
ODOMETRY = "nav_msgs/msg/Odometry"
BATTERY_STATE = "sensor_msgs/msg/BatteryState"
LASER_SCAN = "sensor_msgs/msg/LaserScan"
TYPES = (TWIST, TWIST_STAMPED, ODOMETRY, BATTERY_STATE, LASER_SCAN)

CDR_LE_HEADER = b"\x00\x01\x00\x00"   # encapsulation: plain CDR, little endian, no options
CDR_HEADERS = (b"\x00\x00", b"\x00\x01")  # CDR big / little endian (first two bytes)


class CdrError(SchemaError):
    """Bytes that are not a valid CDR-encoded ROS 2 message of the expected type."""


@lru_cache(maxsize=1)
def typestore():
    """The ROS 2 Humble type store (built once; read-only afterwards)."""
    return get_typestore(Stores.ROS2_HUMBLE)


def msg_class(typename: str):
    """The rosbags message class of ``typename`` (``geometry_msgs/msg/Twist``)."""
    return typestore().types[typename]


def encode(msg, typename: str) -> bytes:
    """``msg`` (a rosbags message object) -> CDR bytes with the encapsulation header."""
    return bytes(typestore().serialize_cdr(msg, typename))


def decode(data: bytes | memoryview, typename: str):
    """CDR bytes -> rosbags message object; :class:`CdrError` names the type and the problem."""
    data = bytes(data)
    if len(data) < 4 or data[:2] not in CDR_HEADERS:
        raise CdrError(f"{typename}: {len(data)} bytes starting {data[:4].hex() or '(empty)'} "
                       "are not CDR (expected the 4-byte encapsulation header 0001 0000)")
    try:
        return typestore().deserialize_cdr(data, typename)
    except Exception as exc:  # rosbags raises struct/index/assertion errors on short data
        raise CdrError(f"{typename}: cannot decode {len(data)} bytes of CDR: "
                       f"{type(exc).__name__}: {exc}") from None


# -- time, angles -------------------------------------------------------------------------------
def time_msg(stamp_ns: int):
    """``builtin_interfaces/msg/Time`` for an integer nanosecond stamp (>= 0)."""
    sec, nanosec = divmod(int(stamp_ns), NS)
    return msg_class("builtin_interfaces/msg/Time")(sec=sec, nanosec=nanosec)


def stamp_ns(header) -> int:
    """Integer nanoseconds of a ``std_msgs/msg/Header`` stamp."""
    return int(header.stamp.sec) * NS + int(header.stamp.nanosec)


def header(stamp: int, frame_id: str):
    """A std_msgs/Header at ``stamp`` [ns] in ``frame_id``."""
    return msg_class("std_msgs/msg/Header")(stamp=time_msg(stamp), frame_id=frame_id)


def yaw_of(q) -> float:
    """Yaw [rad] of a quaternion (x, y, z, w attributes), ZYX convention; roll/pitch ignored."""
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def quaternion_of_yaw(yaw: float):
    """A geometry_msgs/Quaternion of a rotation by ``yaw`` [rad] about z."""
    half = 0.5 * yaw
    return msg_class("geometry_msgs/msg/Quaternion")(x=0.0, y=0.0, z=math.sin(half),
                                                     w=math.cos(half))


def _vec3(x: float = 0.0, y: float = 0.0, z: float = 0.0):
    return msg_class("geometry_msgs/msg/Vector3")(x=float(x), y=float(y), z=float(z))


# -- builders ---------------------------------------------------------------------------------
def twist(v: float, w: float):
    """``geometry_msgs/Twist`` with linear.x = v [m/s], angular.z = w [rad/s], the rest 0."""
    return msg_class(TWIST)(linear=_vec3(x=v), angular=_vec3(z=w))


def twist_stamped(v: float, w: float, stamp: int, frame_id: str = "base_link"):
    """``geometry_msgs/TwistStamped``: :func:`twist` with a header (stamp [ns], frame)."""
    return msg_class(TWIST_STAMPED)(header=header(stamp, frame_id), twist=twist(v, w))


def odometry(stamp: int, x: float, y: float, yaw: float, v: float, w: float,
             frame_id: str = "odom", child_frame_id: str = "base_link"):
    """Planar ``nav_msgs/Odometry``: pose in ``frame_id``, twist in ``child_frame_id``."""
    point = msg_class("geometry_msgs/msg/Point")(x=float(x), y=float(y), z=0.0)
    pose = msg_class("geometry_msgs/msg/Pose")(position=point, orientation=quaternion_of_yaw(yaw))
    tw = msg_class("geometry_msgs/msg/Twist")(linear=_vec3(x=v), angular=_vec3(z=w))
    cov = np.zeros(36, dtype=np.float64)
    return msg_class(ODOMETRY)(
        header=header(stamp, frame_id), child_frame_id=child_frame_id,
        pose=msg_class("geometry_msgs/msg/PoseWithCovariance")(pose=pose, covariance=cov),
        twist=msg_class("geometry_msgs/msg/TwistWithCovariance")(twist=tw, covariance=cov.copy()))


def battery_state(stamp: int, voltage: float, frame_id: str = ""):
    """``sensor_msgs/BatteryState`` as the ROSbot publishes it: voltage only, the rest unknown."""
    cls = msg_class(BATTERY_STATE)
    nan = math.nan
    return cls(header=header(stamp, frame_id), voltage=float(voltage), temperature=nan,
               current=nan, charge=nan, capacity=nan, design_capacity=nan, percentage=nan,
               power_supply_status=cls.POWER_SUPPLY_STATUS_DISCHARGING,
               power_supply_health=cls.POWER_SUPPLY_HEALTH_UNKNOWN,
               power_supply_technology=cls.POWER_SUPPLY_TECHNOLOGY_LION, present=True,
               cell_voltage=np.zeros(0, np.float32), cell_temperature=np.zeros(0, np.float32),
               location="", serial_number="")


def laser_scan(stamp: int, angle_min: float, angle_increment: float, range_min: float,
               range_max: float, ranges, frame_id: str = "laser", scan_time: float = 0.1):
    """``sensor_msgs/LaserScan``; ``ranges`` [m] as float32 (inf/nan kept as given)."""
    r = np.asarray(ranges, dtype=np.float32)
    n = len(r)
    return msg_class(LASER_SCAN)(
        header=header(stamp, frame_id), angle_min=float(angle_min),
        angle_max=float(angle_min + angle_increment * max(n - 1, 0)),
        angle_increment=float(angle_increment), time_increment=float(scan_time / max(n, 1)),
        scan_time=float(scan_time), range_min=float(range_min), range_max=float(range_max),
        ranges=r, intensities=np.zeros(0, np.float32))
