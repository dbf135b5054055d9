"""nodes/ros_face/core.py: our messages -> the face's ROS 2 topics, /goal_pose -> Goal.

Outputs are decoded with a rosbags Jazzy store built here, not the module's own codec.
"""

from __future__ import annotations

import math

import pytest
from rosbags.typesys import Stores, get_typestore

from common import rmw_zenoh as rz
from common.errors import SchemaError
from nodes.ros_face.core import FACE_TOPICS, GOAL_TOPIC, POSE_STAMPED, FaceCore
from schemas import Goal
from schemas.messages import BatteryState, Odometry, PlannerState, Scan, Twist
from tests.support.messages import planner_debug

STORE = get_typestore(Stores.ROS2_JAZZY)
STATE = PlannerState(stamp_ns=2_000_000_000, algorithm="papf", force=(1.0, 0.0),
                     predicted_path=((0.0, 0.0), (1.0, 0.0)),
                     debug=planner_debug("papf", top_quarks=[(2.0, 1.0)]))


def decoded(outputs):
    return {t: STORE.deserialize_cdr(d, FACE_TOPICS[t].typename) for t, d in outputs}


def test_every_stack_topic_becomes_its_ros_topics():
    core = FaceCore()
    out = decoded(core.on_message("odom", Odometry(stamp_ns=1_500_000_000, x=1.0, y=2.0,
                                                    yaw=math.pi / 2, v=0.3, w=0.1)))
    assert out["odom"].pose.pose.position.x == 1.0 and out["odom"].header.frame_id == "odom"
    tf, = out["tf"].transforms
    assert (tf.header.frame_id, tf.child_frame_id) == ("odom", "base_link")
    assert tf.header.stamp.sec == 1 and tf.header.stamp.nanosec == 500_000_000
    scan = decoded(core.on_message("scan", Scan(stamp_ns=1, angle_min=-math.pi, angle_increment=0.5,
                                                range_min=0.2, range_max=25.0,
                                                ranges=[1.0] * 12)))["scan"]
    assert scan.header.frame_id == "laser" and len(scan.ranges) == 12
    assert decoded(core.on_message("cmd_vel", Twist(stamp_ns=1, v=0.2, w=-0.1)))[
        "cmd_vel"].angular.z == pytest.approx(-0.1)
    bat = decoded(core.on_message("battery", BatteryState(stamp_ns=1, voltage=11.8, current=1.5,
                                                          power=17.7, charge_used_mAh=2.0, energy_J=3.0)))
    assert bat["battery"].voltage == pytest.approx(11.8)
    mind = decoded(core.on_message("planner/state", STATE))
    assert [(p.pose.position.x, p.pose.position.y) for p in mind["plan"].poses] == [(0, 0), (1, 0)]
    assert mind["markers"].markers
    static = decoded(core.static())
    assert static["tf_static"].transforms[0].child_frame_id == "laser"
    assert "<robot" in static["robot_description"].data


def test_latched_topics_are_transient_local_and_nodes_stand_for_ours():
    assert FACE_TOPICS["robot_description"].qos.durability == 1        # transient local
    assert FACE_TOPICS["tf_static"].qos == rz.LATCHED
    assert {t for t, s in FACE_TOPICS.items() if s.node == "planner"} == {"cmd_vel", "plan",
                                                                          "markers"}
    assert GOAL_TOPIC.node == "planner" and GOAL_TOPIC.typename == POSE_STAMPED


def _pose(x, y, frame="odom") -> bytes:
    c = STORE.types
    now = c["builtin_interfaces/msg/Time"](sec=3, nanosec=0)
    msg = c[POSE_STAMPED](header=c["std_msgs/msg/Header"](stamp=now, frame_id=frame),
                          pose=c["geometry_msgs/msg/Pose"](
                              position=c["geometry_msgs/msg/Point"](x=x, y=y, z=0.0),
                              orientation=c["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0,
                                                                            w=1.0)))
    return bytes(STORE.serialize_cdr(msg, POSE_STAMPED))


def test_goal_pose_becomes_our_goal_keeping_the_runs_tolerance():
    core = FaceCore()
    assert core.goal_from_pose(_pose(3.0, -1.0)) == Goal(stamp_ns=0, x=3.0, y=-1.0)
    core.on_message("goal", Goal(stamp_ns=5, x=10.0, y=0.0, tolerance=0.3, auth="abc"))
    core.on_message("odom", Odometry(stamp_ns=7, x=0.0, y=0.0, yaw=0.0, v=0.0, w=0.0))
    g = core.goal_from_pose(_pose(4.0, 2.0, ""))
    assert (g.x, g.y, g.tolerance, g.stamp_ns, g.auth) == (4.0, 2.0, 0.3, 7, "")
    assert core.goal_from_pose(_pose(1.0, 1.0, "map")).x == 1.0   # map -> odom: the identity
    with pytest.raises(SchemaError, match="frame 'base_link'"):
        core.goal_from_pose(_pose(1.0, 1.0, "base_link"))
    with pytest.raises(SchemaError, match="not finite"):
        core.goal_from_pose(_pose(math.nan, 1.0))
    with pytest.raises(SchemaError, match="not a CDR PoseStamped"):
        core.goal_from_pose(b"\x00\x01\x00\x00garbage")


def test_rviz_config_shows_every_face_topic():
    from pathlib import Path

    import yaml

    cfg = yaml.safe_load((Path(__file__).parents[2] / "docs" / "ros2-face.rviz").read_text())
    manager = cfg["Visualization Manager"]
    assert manager["Global Options"]["Fixed Frame"] == "odom"
    topics = {d["Topic"]["Value"] for d in manager["Displays"] if "Topic" in d}
    topics.add(next(d for d in manager["Displays"]
                    if d["Class"].endswith("RobotModel"))["Description Topic"]["Value"])
    assert topics == {"/scan", "/odom", "/plan", "/markers", "/robot_description", "/map"}
    qos = {d["Topic"]["Value"]: d["Topic"] for d in manager["Displays"] if "Topic" in d}
    assert qos["/scan"]["Reliability Policy"] == "Best Effort"            # sensor data
    assert qos["/map"]["Durability Policy"] == "Transient Local"
    assert any(d["Class"].endswith("/TF") for d in manager["Displays"])   # /tf, /tf_static
    goal, = [t for t in manager["Tools"] if t["Class"].endswith("SetGoal")]
    assert goal["Topic"]["Value"] == "/goal_pose"
