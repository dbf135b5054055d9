"""Decode whatever travels on a Zenoh key, for people to read (pure; no Zenoh here).

Our msgpack messages name their type (:mod:`schemas`); ROS 2 CDR does not, so its type
comes from the key (rmw_zenoh's keys, the bridge's :data:`ROS_TYPES`) or ``--ros-type``
(:func:`decode`); anything else is shown as its size and first bytes. Used by ``papf
topic``.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, NamedTuple

import msgpack
import numpy as np

from common import rmw_zenoh, ros2
from common.errors import SchemaError
from common.text import MAX_TEXT_CHARS, safe_text  # noqa: F401  (papf.bus's names for them)
from nodes.recorder.writer import peek_stamp
from schemas.messages import BY_TYPE

MSGPACK = "msgpack"
CDR = "cdr"
RAW = "bytes"

# ROS 2 topic (bridge key without the bridge namespace) -> message type. The ROSbot's own
# (docs/robot.md) first, then the topics a ROSbot 2.0 PRO also publishes.
ROS_TYPES = {
    "cmd_vel": ros2.TWIST,
    "odometry/filtered": ros2.ODOMETRY,
    "battery": ros2.BATTERY_STATE,
    "scan": ros2.LASER_SCAN,
    "odom": ros2.ODOMETRY,
    "imu/data": "sensor_msgs/msg/Imu",
    "joint_states": "sensor_msgs/msg/JointState",
    "tf": "tf2_msgs/msg/TFMessage",
    "tf_static": "tf2_msgs/msg/TFMessage",
}
MSGPACK_MAP_FIRST = {*range(0x80, 0x90), 0xDE, 0xDF}   # fixmap, map16, map32


class Decoded(NamedTuple):
    encoding: str            # msgpack | cdr | bytes
    type_name: str           # papf/Scan/v1, sensor_msgs/msg/LaserScan, or "" if unknown
    value: Any               # dict of fields, or a one-line description
    stamp_ns: int | None     # the message's own stamp, if it has one
    error: str = ""          # why the payload did not decode as its type


def ros_type_for_key(key: str) -> str | None:
    """ROS 2 type of a key: an rmw_zenoh key names it (``0/scan/sensor_msgs::msg::dds_::
    LaserScan_/RIHS01_…``); a bridge key ``scan`` or ``<bridge-ns>/scan`` -> LaserScan; else None."""
    parts = key.strip("/").split("/")
    if len(parts) >= 4 and parts[-1].startswith("RIHS01_") and "::dds_::" in parts[-2]:
        try:
            return rmw_zenoh.ros_type_name(parts[-2])
        except SchemaError:
            return None
    for i in range(len(parts)):
        found = ROS_TYPES.get("/".join(parts[i:]))
        if found:
            return found
    return None


def is_cdr(data: bytes) -> bool:
    """The 4-byte CDR encapsulation header (plain CDR, either endianness, no options)."""
    return len(data) >= 4 and data[:2] in ros2.CDR_HEADERS and data[2:4] == b"\x00\x00"


def decode(key: str, data: bytes, ros_type: str | None = None) -> Decoded:
    """What ``data`` published on ``key`` holds.

    Two encodings share the bus (docs/robot.md): our messages are msgpack maps that name
    their type (``"_type": "papf/Scan/v1"``, :mod:`schemas`); the ROS 2 topics that
    ``zenoh-bridge-ros2dds`` carries are CDR with a 4-byte encapsulation header, and CDR
    does not name its type, so it is taken from the key (rmw_zenoh's keys name it; on the
    bridge :data:`ROS_TYPES`: the ROSbot's topics, optionally under a bridge namespace) or
    given with ``--ros-type``.
    Anything else is shown as its size and first bytes.
    """
    data = bytes(data)
    if data and data[0] in MSGPACK_MAP_FIRST:
        return _decode_msgpack(data)
    if is_cdr(data):
        return _decode_cdr(key, data, ros_type)
    return Decoded(RAW, "", f"{len(data)} bytes: {data[:16].hex()}{'…' if len(data) > 16 else ''}",
                   None)


def stamp_of(key: str, data: bytes, ros_type: str | None = None) -> int | None:
    """The message's own stamp [ns] without decoding a big msgpack payload whole; None if none."""
    data = bytes(data)
    if data and data[0] in MSGPACK_MAP_FIRST:
        return peek_stamp(data)
    return decode(key, data, ros_type).stamp_ns if is_cdr(data) else None


def _decode_msgpack(data: bytes) -> Decoded:
    try:
        wire = msgpack.unpackb(data, raw=False, strict_map_key=False)
    except Exception as exc:  # msgpack raises several unrelated types
        return Decoded(RAW, "", f"{len(data)} bytes, not msgpack", None, str(exc))
    type_name = wire.get("_type", "") if isinstance(wire, dict) else ""
    msg_type = BY_TYPE.get(type_name)
    if msg_type is None:
        return Decoded(MSGPACK, str(type_name), plain(wire), None,
                       f"unknown message type {type_name!r}" if type_name else "")
    try:
        msg = msg_type.from_wire(wire)
    except SchemaError as exc:
        return Decoded(MSGPACK, type_name, plain(wire), None, str(exc))
    return Decoded(MSGPACK, type_name, msg.to_dict(), getattr(msg, "stamp_ns", None))


def _decode_cdr(key: str, data: bytes, ros_type: str | None) -> Decoded:
    type_name = ros_type or ros_type_for_key(key)
    if type_name is None:
        return Decoded(CDR, "", f"{len(data)} bytes of CDR (type unknown: give --ros-type, "
                                "e.g. sensor_msgs/msg/LaserScan)", None)
    if type_name not in ros2.typestore().types:
        return Decoded(CDR, type_name, f"{len(data)} bytes of CDR", None,
                       f"{type_name!r} is not a ROS 2 Humble type (e.g. geometry_msgs/msg/Twist)")
    try:
        msg = ros2.decode(data, type_name)
    except SchemaError as exc:
        return Decoded(CDR, type_name, f"{len(data)} bytes of CDR", None, str(exc))
    stamp = ros2.stamp_ns(msg.header) if hasattr(msg, "header") else None
    return Decoded(CDR, type_name, plain(msg), stamp)


def plain(value: Any) -> Any:
    """rosbags messages, numpy arrays, bytes and tuples -> dicts, lists and scalars."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: plain(getattr(value, f.name)) for f in dataclasses.fields(value)
                if not f.name.startswith("__") and not f.name.isupper()}   # UPPER: a ROS 2 constant
    if isinstance(value, np.ndarray):
        return value.astype(float).tolist() if value.dtype.kind == "f" else value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, dict):
        return {str(k): plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if isinstance(value, (bytes, bytearray)):
        return f"<{len(value)} bytes>"
    return value


# -- text -----------------------------------------------------------------------------------------
def _scalar(v: Any) -> str:
    if isinstance(v, float):
        return repr(v) if math.isfinite(v) else str(v)
    if isinstance(v, str):
        v = safe_text(v)
        return repr(v) if (not v or v != v.strip() or ":" in v) else v
    return safe_text(str(v))


def as_text(value: Any, max_items: int | None = 8, indent: int = 0) -> str:
    """YAML-like lines, as ``ros2 topic echo`` prints; arrays cut at ``max_items`` (None: all)."""
    pad = "  " * indent
    if not isinstance(value, dict):
        return pad + _scalar(value)
    lines = []
    for k, v in value.items():
        k = safe_text(str(k), 80)
        if isinstance(v, dict):
            lines.append(f"{pad}{k}:")
            lines.append(as_text(v, max_items, indent + 1))
        elif isinstance(v, list):
            lines.append(f"{pad}{k}: {_list_text(v, max_items)}")
        else:
            lines.append(f"{pad}{k}: {_scalar(v)}")
    return "\n".join(lines)


def _list_text(v: list, max_items: int | None) -> str:
    shown = v if max_items is None or len(v) <= max_items else v[:max_items]
    items = ", ".join(_list_text(x, max_items) if isinstance(x, list) else
                      (_short_dict(x) if isinstance(x, dict) else _scalar(x)) for x in shown)
    more = f", … ({len(v)} items; --full shows all)" if len(shown) < len(v) else ""
    return f"[{items}{more}]"


def _short_dict(d: dict) -> str:
    return "{" + ", ".join(f"{k}: {_scalar(v)}" for k, v in d.items()) + "}"


def json_safe(value: Any, max_chars: int | None = None) -> Any:
    """Non-finite floats as the strings "nan", "inf", "-inf" (JSON has no such numbers);
    strings cut at ``max_chars`` (None: whole; json.dumps escapes control characters)."""
    if isinstance(value, float) and not math.isfinite(value):
        return str(value)
    if isinstance(value, str) and max_chars is not None and len(value) > max_chars:
        return value[:max_chars] + f"… ({len(value):,} chars)"
    if isinstance(value, dict):
        return {k: json_safe(v, max_chars) for k, v in value.items()}
    if isinstance(value, list):
        return [json_safe(v, max_chars) for v in value]
    return value
