"""CDR against rosbags (ROS 2 Humble typestore): what crosses zenoh-bridge-ros2dds."""

from __future__ import annotations

import math

import numpy as np
import pytest
from rosbags.typesys import Stores, get_typestore

from common import ros2
from common.errors import SchemaError
from nodes.base_driver.rosbot import (
    cdr_to_robot_odom,
    cdr_to_twist,
    cdr_to_voltage,
    twist_to_cdr,
)
from nodes.lidar_sim.ros2_source import classify, laserscan_to_scan, resample

TS = get_typestore(Stores.ROS2_HUMBLE)   # an independent store: rosbags, not our helpers
INF, NAN = math.inf, math.nan


def _rosbags(msg_type: str, **fields):
    return TS.types[msg_type](**fields)


def _vec(x=0.0, y=0.0, z=0.0):
    return _rosbags("geometry_msgs/msg/Vector3", x=x, y=y, z=z)


def _header(sec=12, nanosec=345, frame="odom"):
    return _rosbags("std_msgs/msg/Header",
                    stamp=_rosbags("builtin_interfaces/msg/Time", sec=sec, nanosec=nanosec),
                    frame_id=frame)


# -- Twist: the bytes the driver puts on cmd_vel ------------------------------------------------
@pytest.mark.parametrize("v, w", [(0.3, -1.2), (0.0, 0.0), (-0.9, 3.0), (0.123456789, 1e-9)])
def test_driver_cmd_vel_bytes_decode_with_rosbags(v, w):
    data = twist_to_cdr(v, w)
    assert data[:4] == b"\x00\x01\x00\x00"          # CDR little endian encapsulation header
    assert len(data) == 4 + 6 * 8                    # two Vector3 of float64
    msg = TS.deserialize_cdr(data, "geometry_msgs/msg/Twist")
    assert (msg.linear.x, msg.angular.z) == (v, w)
    assert (msg.linear.y, msg.linear.z, msg.angular.x, msg.angular.y) == (0.0, 0.0, 0.0, 0.0)


def test_twist_from_rosbags_both_endiannesses():
    msg = _rosbags("geometry_msgs/msg/Twist", linear=_vec(0.5, 0.1), angular=_vec(z=-0.7))
    for little in (True, False):
        data = bytes(TS.serialize_cdr(msg, "geometry_msgs/msg/Twist", little_endian=little))
        assert cdr_to_twist(data) == (0.5, -0.7)


# -- Odometry -----------------------------------------------------------------------------------
def test_odometry_round_trip():
    data = ros2.encode(ros2.odometry(1_500_000_123, 1.25, -0.5, 2.0, 0.4, -0.3), ros2.ODOMETRY)
    msg = TS.deserialize_cdr(data, "nav_msgs/msg/Odometry")
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec) == (1, 500_000_123)
    assert (msg.header.frame_id, msg.child_frame_id) == ("odom", "base_link")
    assert (msg.pose.pose.position.x, msg.pose.pose.position.y) == (1.25, -0.5)
    assert msg.pose.pose.orientation.z == pytest.approx(math.sin(1.0))
    assert (msg.twist.twist.linear.x, msg.twist.twist.angular.z) == (0.4, -0.3)
    odom = cdr_to_robot_odom(data)
    assert odom.stamp_ns == 1_500_000_123
    assert odom.pose.yaw == pytest.approx(2.0)
    assert (odom.pose.x, odom.pose.y, odom.v, odom.w) == (1.25, -0.5, 0.4, -0.3)


def test_odometry_built_by_rosbags_decodes():
    q = _rosbags("geometry_msgs/msg/Quaternion", x=0.0, y=0.0, z=math.sin(-0.4), w=math.cos(-0.4))
    pose = _rosbags("geometry_msgs/msg/Pose",
                    position=_rosbags("geometry_msgs/msg/Point", x=3.0, y=4.0, z=0.1),
                    orientation=q)
    msg = _rosbags(
        "nav_msgs/msg/Odometry", header=_header(), child_frame_id="base_link",
        pose=_rosbags("geometry_msgs/msg/PoseWithCovariance", pose=pose,
                      covariance=np.arange(36, dtype=np.float64)),
        twist=_rosbags("geometry_msgs/msg/TwistWithCovariance",
                       twist=_rosbags("geometry_msgs/msg/Twist", linear=_vec(0.2),
                                      angular=_vec(z=0.1)),
                       covariance=np.zeros(36)))
    odom = cdr_to_robot_odom(bytes(TS.serialize_cdr(msg, "nav_msgs/msg/Odometry")))
    assert odom.stamp_ns == 12 * 10**9 + 345
    assert (odom.pose.x, odom.pose.y, odom.v, odom.w) == (3.0, 4.0, 0.2, 0.1)
    assert odom.pose.yaw == pytest.approx(-0.8)


# -- BatteryState -------------------------------------------------------------------------------
def test_battery_state_round_trip():
    data = ros2.encode(ros2.battery_state(7, 11.84), ros2.BATTERY_STATE)
    msg = TS.deserialize_cdr(data, "sensor_msgs/msg/BatteryState")
    assert msg.voltage == pytest.approx(11.84)             # float32 on the wire
    assert math.isnan(msg.current) and math.isnan(msg.percentage)
    assert msg.power_supply_technology == 2                # LION
    assert cdr_to_voltage(data) == pytest.approx(11.84, abs=1e-6)


def test_battery_state_from_rosbags_and_bad_voltage():
    cls = TS.types["sensor_msgs/msg/BatteryState"]
    base = dict(header=_header(frame=""), temperature=NAN, current=NAN, charge=NAN, capacity=NAN,
                design_capacity=NAN, percentage=NAN, power_supply_status=0,
                power_supply_health=0, power_supply_technology=0, present=True,
                cell_voltage=np.zeros(3, np.float32), cell_temperature=np.zeros(0, np.float32),
                location="", serial_number="")
    good = bytes(TS.serialize_cdr(cls(voltage=12.5, **base), "sensor_msgs/msg/BatteryState"))
    assert cdr_to_voltage(good) == 12.5
    bad = bytes(TS.serialize_cdr(cls(voltage=NAN, **base), "sensor_msgs/msg/BatteryState"))
    with pytest.raises(ros2.CdrError, match="voltage nan"):
        cdr_to_voltage(bad)


# -- LaserScan ----------------------------------------------------------------------------------
def test_laser_scan_round_trip_keeps_inf_nan():
    ranges = np.array([1.0, INF, NAN, 0.0, 30.0, 0.1], np.float32)
    data = ros2.encode(ros2.laser_scan(5, -math.pi, 0.5, 0.2, 25.0, ranges), ros2.LASER_SCAN)
    msg = TS.deserialize_cdr(data, "sensor_msgs/msg/LaserScan")
    np.testing.assert_array_equal(msg.ranges, ranges)      # inf/nan/0 untouched on the wire
    assert msg.angle_max == pytest.approx(-math.pi + 2.5)
    assert (msg.range_min, msg.range_max) == (pytest.approx(0.2), 25.0)


def test_laser_scan_from_rosbags_to_our_scan():
    n = 720
    ranges = np.full(n, 5.0, np.float32)
    ranges[359:362] = 1.0                                   # an obstacle straight ahead (angle 0)
    msg = _rosbags("sensor_msgs/msg/LaserScan", header=_header(frame="laser"),
                   angle_min=-math.pi, angle_max=math.pi - 2 * math.pi / n,
                   angle_increment=2 * math.pi / n, time_increment=0.0, scan_time=0.1,
                   range_min=0.2, range_max=25.0, ranges=ranges,
                   intensities=np.zeros(n, np.float32))
    scan = laserscan_to_scan(bytes(TS.serialize_cdr(msg, "sensor_msgs/msg/LaserScan")), 42)
    assert (scan.stamp_ns, len(scan.ranges), scan.angle_min) == (42, 300, -math.pi)
    assert scan.angle_increment == pytest.approx(2 * math.pi / 300)
    assert scan.ranges[150] == 1.0                          # beam 150 of 300 points at angle 0
    assert np.count_nonzero(scan.ranges == 1.0) == 1 and np.all(scan.ranges[:149] == 5.0)


# -- resampling and RPLIDAR readings ------------------------------------------------------------
def test_classify_rplidar_readings():
    out = classify(np.array([1.0, INF, -INF, 0.0, 0.1, 30.0, NAN]), 0.2, 25.0)
    assert out[0] == 1.0 and np.all(np.isinf(out[1:6])) and np.all(out[1:6] > 0)
    assert math.isnan(out[6])


def test_resample_same_geometry_is_identity():
    r = np.linspace(0.5, 3.0, 300)
    np.testing.assert_allclose(resample(r, -math.pi, 2 * math.pi / 300, 0.2, 25.0, 300), r,
                               rtol=1e-6)


def test_resample_bin_takes_nearest_return_then_no_return_then_invalid():
    n = 900                       # three source readings per output beam of 300
    r = np.full(n, 4.0)
    r[899], r[0], r[1] = 3.0, 2.0, 5.0   # bin 0 = readings 899 (wrapping round), 0, 1
    r[14:17] = INF, NAN, INF             # bin 5: "no return" beats invalid
    r[29:32] = NAN                       # bin 10: only invalid readings
    out = resample(r, -math.pi, 2 * math.pi / n, 0.2, 25.0, 300)
    assert out[0] == 2.0 and math.isinf(out[5]) and math.isnan(out[10]) and out[7] == 4.0


def test_resample_clockwise_scan_and_coarse_scan():
    n = 100                       # clockwise from +pi, coarser than the output: nearest reading
    angles = math.pi - 2 * math.pi / n * np.arange(n)
    r = 1.0 + np.cos(angles)      # a smooth function of the angle
    out = resample(r, math.pi, -2 * math.pi / n, 0.0, 25.0, 300)
    expect = 1.0 + np.cos(-math.pi + 2 * math.pi / 300 * np.arange(300))
    assert np.max(np.abs(out - expect)) < 2 * math.pi / n   # within one source step of cos
    assert np.all(np.isfinite(out))


def test_resample_partial_field_of_view_is_nan_outside():
    r = np.full(91, 2.0)          # a 90 deg scan around the front
    out = resample(r, -math.pi / 4, math.pi / 180 / 1.0 * 1.0, 0.2, 25.0, 360)
    front = out[180 - 40: 180 + 40]
    assert np.all(front == 2.0) and np.all(np.isnan(out[:100])) and np.all(np.isnan(out[260:]))


@pytest.mark.parametrize("data", [b"", b"\x00\x01", b"\x07\x07\x00\x00" + b"\x00" * 48,
                                  b"\x00\x01\x00\x00\x01"])
def test_bad_bytes_raise_cdr_error(data):
    with pytest.raises(SchemaError):
        cdr_to_twist(data)
    with pytest.raises(SchemaError):
        laserscan_to_scan(data, 0)


def test_echo_prints_a_messages_fields_not_its_constants():
    from papf.bus.decode import decode

    data = ros2.encode(ros2.battery_state(1, 11.9), ros2.BATTERY_STATE)
    shown = decode("battery", data).value
    assert shown["voltage"] == pytest.approx(11.9)
    assert not [k for k in shown if k.isupper()], shown.keys()   # POWER_SUPPLY_STATUS_… gone
