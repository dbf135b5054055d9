"""A rosbag2 as ``ros2 bag record`` on the ROSbot would write it, by rosbags' own Writer.

The messages are built from rosbags' ROS 2 Jazzy types here (not by common.ros2_convert),
so what the bag holds and what this module knows about it come from code that is not the
reader's. The drive: ``IDLE_S`` standing, then ``MOVE_S`` along a circular arc (radius
``RADIUS_M``, speed ``SPEED``), then ``IDLE_S`` standing; the pack draws ``IDLE_A`` standing
and ``MOVE_A`` moving (ROS sign convention: negative ``current`` while discharging).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

TS = get_typestore(Stores.ROS2_JAZZY)
T = TS.types
EPOCH_NS = 1_733_140_000_000_000_000   # [ns] header stamps: wall time, as on the robot
ODOM_HZ, BATTERY_HZ, SCAN_HZ, CMD_HZ = 50, 10, 10, 10
IDLE_S, MOVE_S = 2.0, 20.0             # [s]
SPEED, RADIUS_M = 0.5, 2.0             # [m/s], [m]
IDLE_A, MOVE_A = 1.2, 2.0              # [A] discharge
VOLTAGE = 11.6                         # [V]


@dataclass(frozen=True)
class Truth:
    """What the writer knows of its bag."""

    path_length_m: float
    duration_s: float          # first to last moving sample
    charge_mAh: float          # ∫ I dt over the odometry's span
    span_s: float              # first to last odometry sample


def _stamp(t_ns: int):
    sec, nsec = divmod(EPOCH_NS + t_ns, 1_000_000_000)
    return T["builtin_interfaces/msg/Time"](sec=sec, nanosec=nsec)


def _header(t_ns: int, frame: str):
    return T["std_msgs/msg/Header"](stamp=_stamp(t_ns), frame_id=frame)


def _vec(x=0.0, y=0.0, z=0.0):
    return T["geometry_msgs/msg/Vector3"](x=x, y=y, z=z)


def _moving(t_s: float) -> bool:
    return IDLE_S <= t_s < IDLE_S + MOVE_S


def pose_at(t_s: float) -> tuple[float, float, float, float, float]:
    """(x, y, yaw, v, w) of the drive at ``t_s``: an arc of RADIUS_M around (0, RADIUS_M)."""
    s = SPEED * min(max(t_s - IDLE_S, 0.0), MOVE_S)
    th = s / RADIUS_M
    v, w = (SPEED, SPEED / RADIUS_M) if _moving(t_s) else (0.0, 0.0)
    return RADIUS_M * math.sin(th), RADIUS_M * (1 - math.cos(th)), th, v, w


def odometry(t_ns: int):
    x, y, yaw, v, w = pose_at(t_ns / 1e9)
    q = T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2))
    pose = T["geometry_msgs/msg/Pose"](position=T["geometry_msgs/msg/Point"](x=x, y=y, z=0.0),
                                       orientation=q)
    return T["nav_msgs/msg/Odometry"](
        header=_header(t_ns, "odom"), child_frame_id="base_link",
        pose=T["geometry_msgs/msg/PoseWithCovariance"](pose=pose, covariance=np.zeros(36)),
        twist=T["geometry_msgs/msg/TwistWithCovariance"](
            twist=T["geometry_msgs/msg/Twist"](linear=_vec(v), angular=_vec(z=w)),
            covariance=np.zeros(36)))


def battery(t_ns: int, with_current: bool):
    cls = T["sensor_msgs/msg/BatteryState"]
    current = -(MOVE_A if _moving(t_ns / 1e9) else IDLE_A) if with_current else math.nan
    return cls(header=_header(t_ns, ""), voltage=VOLTAGE, temperature=math.nan, current=current,
               charge=math.nan, capacity=math.nan, design_capacity=math.nan,
               percentage=math.nan, power_supply_status=cls.POWER_SUPPLY_STATUS_DISCHARGING,
               power_supply_health=0, power_supply_technology=2, present=True,
               cell_voltage=np.zeros(0, np.float32), cell_temperature=np.zeros(0, np.float32),
               location="", serial_number="")


def scan(t_ns: int):
    n = 720
    return T["sensor_msgs/msg/LaserScan"](
        header=_header(t_ns, "laser"), angle_min=-math.pi, angle_max=math.pi - 2 * math.pi / n,
        angle_increment=2 * math.pi / n, time_increment=0.1 / n, scan_time=0.1, range_min=0.2,
        range_max=25.0, ranges=np.full(n, 3.0, np.float32), intensities=np.zeros(0, np.float32))


def twist(t_ns: int):
    _x, _y, _yaw, v, w = pose_at(t_ns / 1e9)
    return T["geometry_msgs/msg/Twist"](linear=_vec(v), angular=_vec(z=w))


def tf(t_ns: int):
    x, y, yaw, _v, _w = pose_at(t_ns / 1e9)
    tr = T["geometry_msgs/msg/Transform"](
        translation=_vec(x, y), rotation=T["geometry_msgs/msg/Quaternion"](
            x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2)))
    return T["tf2_msgs/msg/TFMessage"](transforms=[T["geometry_msgs/msg/TransformStamped"](
        header=_header(t_ns, "odom"), child_frame_id="base_link", transform=tr)])


TOPICS = {  # role: (default topic, type, rate [Hz], builder)
    "odom": ("/odometry/filtered", "nav_msgs/msg/Odometry", ODOM_HZ, odometry),
    "battery": ("/battery", "sensor_msgs/msg/BatteryState", BATTERY_HZ, battery),
    "cmd_vel": ("/cmd_vel", "geometry_msgs/msg/Twist", CMD_HZ, twist),
    "scan": ("/scan", "sensor_msgs/msg/LaserScan", SCAN_HZ, scan),
    "tf": ("/tf", "tf2_msgs/msg/TFMessage", ODOM_HZ, tf),
}


def write_bag(path: Path, storage: str = "mcap", with_current: bool = True,
              names: dict[str, str] | None = None, leave_out: tuple[str, ...] = ()) -> Truth:
    """Write the drive to ``path`` (a new rosbag2 directory); ``names``: role -> topic."""
    plugin = {"mcap": StoragePlugin.MCAP, "sqlite3": StoragePlugin.SQLITE3}[storage]
    total_s = 2 * IDLE_S + MOVE_S
    rows = []
    with Writer(path, version=9, storage_plugin=plugin) as w:
        for role, (topic, msgtype, hz, build) in TOPICS.items():
            if role in leave_out:
                continue
            conn = w.add_connection((names or {}).get(role, topic), msgtype, typestore=TS)
            period = 1_000_000_000 // hz
            for k in range(int(total_s * hz) + 1):
                t = k * period
                msg = build(t, with_current) if role == "battery" else build(t)
                # logged 3 ms after the stamp (transport), as a recorder receives it
                rows.append((EPOCH_NS + t + 3_000_000, conn, TS.serialize_cdr(msg, msgtype)))
        for log_ns, conn, data in sorted(rows, key=lambda r: r[0]):
            w.write(conn, log_ns, data)
    charge_As = IDLE_A * 2 * IDLE_S + MOVE_A * MOVE_S
    return Truth(path_length_m=SPEED * MOVE_S, duration_s=MOVE_S, charge_mAh=charge_As / 3.6,
                 span_s=total_s)
