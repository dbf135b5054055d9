"""common.ros2_convert and common.urdf: every conversion decoded back with rosbags' own codec."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from rosbags.typesys import Stores, get_typestore

from common import robot
from common import ros2_convert as rc
from common.urdf import rosbot_urdf
from schemas.messages import BatteryState, Odometry, PlannerState, Scan, Twist
from tests.support.messages import planner_debug

# decoded by a store built here, not by the module's own
STORE = get_typestore(Stores.ROS2_JAZZY)


def back(msg, typename: str):
    """Serialize with the module, decode with rosbags' typestore (deserialize_cdr)."""
    data = rc.serialize(msg, typename)
    assert data[:4] == b"\x00\x01\x00\x00"      # CDR little endian encapsulation
    return STORE.deserialize_cdr(data, typename)


def stamp(header) -> int:
    return header.stamp.sec * 1_000_000_000 + header.stamp.nanosec


STATE = PlannerState(stamp_ns=3_250_000_000, algorithm="papf", mode="bypass", force=(3.0, -4.0),
                     temporary_goal=(1.5, 0.5), predicted_path=((0.0, 0.0), (1.0, 0.0), (1.0, 1.0)),
                     debug=planner_debug("papf", abandoned_paths=[[(0.0, 0.0), (0.5, 0.5)],
                                                                  [(0.0, 0.0), (0.5, -0.5)]],
                                         top_quarks=[(2.0, 1.0), (2.5, 1.5)])
                     + planner_debug("arapf", virtual_walls=[[(3.0, 0.0), (3.0, 1.0)]]))


def test_store_is_jazzy():
    assert rc.STORE is Stores.ROS2_JAZZY


def test_laser_scan():
    ranges = np.array([1.0, np.inf, np.nan, 24.5], np.float32)
    scan = Scan(stamp_ns=1_500_000_001, angle_min=-math.pi, angle_increment=0.5, range_min=0.2,
                range_max=25.0, ranges=ranges)
    m = back(rc.laser_scan(scan), rc.LASER_SCAN)
    assert stamp(m.header) == 1_500_000_001 and m.header.frame_id == "laser"
    assert m.angle_min == pytest.approx(-math.pi) and m.angle_increment == pytest.approx(0.5)
    assert m.angle_max == pytest.approx(-math.pi + 1.5)
    assert (m.range_min, m.range_max) == (pytest.approx(0.2), 25.0)
    np.testing.assert_array_equal(m.ranges, ranges)       # inf and nan kept
    assert m.scan_time == pytest.approx(1 / robot.LIDAR_RATE_HZ)
    ours = rc.scan_of(m)
    np.testing.assert_array_equal(ours.ranges, ranges)
    assert ours.stamp_ns == scan.stamp_ns and ours.sensor_x == robot.LIDAR_X_M


def test_odometry_and_tf():
    odo = Odometry(stamp_ns=2_000_000_000, x=1.25, y=-0.5, yaw=2.5, v=0.4, w=-0.3)
    m = back(rc.odometry(odo), rc.ODOMETRY)
    assert (m.header.frame_id, m.child_frame_id) == ("odom", "base_link")
    assert stamp(m.header) == odo.stamp_ns
    assert (m.pose.pose.position.x, m.pose.pose.position.y) == (1.25, -0.5)
    assert rc.yaw_of(m.pose.pose.orientation) == pytest.approx(2.5)
    assert (m.twist.twist.linear.x, m.twist.twist.angular.z) == (0.4, -0.3)
    assert rc.odometry_of(m) == odo
    tf = back(rc.tf_odom(odo), rc.TF_MESSAGE).transforms
    assert len(tf) == 1 and (tf[0].header.frame_id, tf[0].child_frame_id) == ("odom", "base_link")
    assert (tf[0].transform.translation.x, tf[0].transform.translation.y) == (1.25, -0.5)
    assert rc.yaw_of(tf[0].transform.rotation) == pytest.approx(2.5)
    assert stamp(tf[0].header) == odo.stamp_ns


def test_tf_static_is_the_lidar_mount():
    (t,) = back(rc.tf_static(), rc.TF_MESSAGE).transforms
    assert (t.header.frame_id, t.child_frame_id) == ("base_link", "laser")
    tr = t.transform.translation
    assert (tr.x, tr.y, tr.z) == (robot.LIDAR_X_M, robot.LIDAR_Y_M, robot.LIDAR_HEIGHT_M)
    assert rc.yaw_of(t.transform.rotation) == pytest.approx(robot.LIDAR_YAW_RAD)


def test_twist():
    m = back(rc.twist(Twist(stamp_ns=5, v=0.7, w=-1.2)), rc.TWIST)
    assert (m.linear.x, m.linear.y, m.angular.z) == (0.7, 0.0, -1.2)
    assert rc.twist_of(m, 5) == Twist(stamp_ns=5, v=0.7, w=-1.2)


def test_battery_state_ros_sign_convention():
    b = BatteryState(stamp_ns=9, voltage=11.4, current=1.75, power=19.95, charge_used_mAh=12.0,
                     energy_J=400.0, soc=0.8)
    m = back(rc.battery_state(b), rc.BATTERY_STATE)
    assert m.current == pytest.approx(-1.75)            # negative while discharging
    assert m.voltage == pytest.approx(11.4) and m.percentage == pytest.approx(0.8)
    assert m.charge == pytest.approx(0.8 * 3.5) and m.capacity == pytest.approx(3.5)
    assert m.power_supply_status == m.POWER_SUPPLY_STATUS_DISCHARGING
    assert rc.discharge_current_of(m) == pytest.approx(1.75)
    m.current = math.nan                                # unknown current
    assert rc.discharge_current_of(m) is None


def test_path_is_the_prediction():
    m = back(rc.path(STATE), rc.PATH)
    assert m.header.frame_id == "odom" and stamp(m.header) == STATE.stamp_ns
    assert [(p.pose.position.x, p.pose.position.y) for p in m.poses] == list(STATE.predicted_path)
    yaws = [rc.yaw_of(p.pose.orientation) for p in m.poses]
    assert yaws == pytest.approx([0.0, math.pi / 2, math.pi / 2])
    assert back(rc.path(PlannerState(stamp_ns=0, algorithm="apf")), rc.PATH).poses == []


def test_markers_carry_the_mind():
    m = back(rc.markers(STATE, robot_xy=(0.5, 0.25)), rc.MARKER_ARRAY).markers
    cls = STORE.types["visualization_msgs/msg/Marker"]
    assert m[0].action == cls.DELETEALL
    by_id = {(k.ns, k.id): k for k in m[1:]}
    assert all(k.header.frame_id == "odom" and k.action == cls.ADD for k in m[1:])
    assert [(p.x, p.y) for p in by_id["mind", 2].points] == [STATE.temporary_goal]
    arrow = by_id["mind", 3]
    assert arrow.type == cls.ARROW and (arrow.points[0].x, arrow.points[0].y) == (0.5, 0.25)
    dx, dy = arrow.points[1].x - 0.5, arrow.points[1].y - 0.25
    assert math.atan2(dy, dx) == pytest.approx(math.atan2(-4.0, 3.0))
    assert rc.FORCE_MIN_M <= math.hypot(dx, dy) <= rc.FORCE_MAX_M
    # the plug-ins' own values, by kind, each in its own ns, in its declared style
    quarks = by_id["mind/top_quarks", 0]
    assert [(p.x, p.y) for p in quarks.points] == list(STATE.get("top_quarks"))
    assert quarks.type == cls.SPHERE_LIST
    style = STATE.value("top_quarks")
    assert (quarks.color.r, quarks.color.a, quarks.scale.x) == pytest.approx(
        (style.colour[0], style.colour[3], style.size))
    assert [[(p.x, p.y) for p in by_id["mind/abandoned_paths", i].points] for i in (0, 1)] == \
        [list(p) for p in STATE.get("abandoned_paths")]
    wall = by_id["mind/virtual_walls", 0]
    assert [(p.x, p.y) for p in wall.points] == list(STATE.get("virtual_walls")[0])
    assert wall.type == cls.LINE_STRIP
    assert len(m) == 1 + 6       # no virtual obstacle: nothing drawn for it
    # no robot position: no force arrow
    assert ("mind", 3) not in {(k.ns, k.id) for k in back(rc.markers(STATE), rc.MARKER_ARRAY).markers}


def test_markers_show_scalars_and_counts_as_text_above_the_robot():
    state = PlannerState(stamp_ns=1, algorithm="iapf", debug=planner_debug(
        "iapf", lane_goal_y=0.75, local_minimum_count=-2))
    m = back(rc.markers(state, robot_xy=(1.0, 2.0)), rc.MARKER_ARRAY).markers
    cls = STORE.types["visualization_msgs/msg/Marker"]
    texts = {k.ns: k for k in m if k.type == cls.TEXT_VIEW_FACING}
    assert texts["mind/lane_goal_y"].text == "lane goal y 0.75 m"
    assert texts["mind/local_minimum_count"].text == "local minima ahead -2"
    assert (texts["mind/lane_goal_y"].pose.position.x, texts["mind/lane_goal_y"].pose.position.y) \
        == (1.0, 2.0)
    none = PlannerState(stamp_ns=1, algorithm="iapf", debug=planner_debug("iapf"))
    assert not [k for k in back(rc.markers(none, robot_xy=(1.0, 2.0)), rc.MARKER_ARRAY).markers
                if k.ns == "mind/lane_goal_y"]     # nan: no lane goal, no text


def test_marker_colours_are_the_viewers():
    from nodes.viewer.scene import MIND_COLOURS
    assert all(MIND_COLOURS[k] == v for k, v in rc.COLOURS.items())


def test_robot_description_parses_with_links_and_joints():
    m = back(rc.string(rosbot_urdf()), rc.STRING)
    root = ET.fromstring(m.data)
    assert root.tag == "robot"
    links = {e.get("name") for e in root.findall("link")}
    assert links == {"base_link", "laser"} | {f"{w}_wheel_link" for w in
                                              ("front_left", "front_right", "rear_left",
                                               "rear_right")}
    joints = {e.get("name"): e for e in root.findall("joint")}
    assert len(joints) == 5 and all(j.find("parent").get("link") == "base_link"
                                    for j in joints.values())
    laser = joints["laser_joint"]
    assert laser.get("type") == "fixed" and laser.find("child").get("link") == "laser"
    xyz = [float(v) for v in laser.find("origin").get("xyz").split()]
    assert xyz == pytest.approx([robot.LIDAR_X_M, robot.LIDAR_Y_M, robot.LIDAR_HEIGHT_M])
    fl = joints["front_left_wheel_joint"]
    assert fl.get("type") == "continuous" and fl.find("axis").get("xyz") == "0 1 0"
    assert [float(v) for v in fl.find("origin").get("xyz").split()] == pytest.approx(
        [robot.WHEELBASE_M / 2, robot.TRACK_M / 2, robot.WHEEL_RADIUS_M])
    box = root.find("link[@name='base_link']/visual/geometry/box")
    assert [float(v) for v in box.get("size").split()][:2] == pytest.approx(
        [robot.BODY_LENGTH_M, robot.BODY_WIDTH_M])
    masses = sum(float(e.get("value")) for e in root.iter("mass"))
    assert masses == pytest.approx(robot.MASS_KG)
