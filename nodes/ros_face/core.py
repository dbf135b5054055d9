"""The ROS 2 face, pure: our messages -> the ROS 2 topics tools expect, ``/goal_pose`` -> Goal.

:class:`FaceCore` converts with :mod:`common.ros2_convert`; each ROS topic is presented by
the ROS 2 node that stands for the stack node it comes from (:data:`FACE_TOPICS`). No
transport here: used by the face process (:mod:`nodes.ros_face.__main__`). The parameter
services and Nav2's action are :mod:`nodes.ros_face.params` and :mod:`nodes.ros_face.navigate`.
"""

from __future__ import annotations

import dataclasses
import math
from typing import NamedTuple

from common import rmw_zenoh as rz
from common import ros2_convert as rc
from common.errors import SchemaError
from common.ros2_bag import WheelJoints
from common.units import NS_PER_S
from common.urdf import rosbot_urdf
from schemas import Goal

POSE_STAMPED = "geometry_msgs/msg/PoseStamped"
GOAL_FRAMES = ("odom", "map", "")   # /goal_pose frames taken as our world frame (map = odom)
TF_QOS = rz.Qos(depth=100)          # tf2's TransformBroadcaster
CLOCK_QOS = rz.Qos(reliability=2, depth=1)   # rclcpp::ClockQoS: best effort, keep last 1
BATTERY_PERIOD_NS = NS_PER_S        # [ns] /battery at 1 Hz (the meter meters at 50 Hz)
CLOCK_PERIOD_NS = NS_PER_S // 100   # [ns] /clock at most 100 Hz


class FaceTopic(NamedTuple):
    typename: str
    qos: rz.Qos
    node: str          # the stack node this topic comes from (its ROS node: papf_<node>)


# ROS topic (relative to --ros-namespace) -> what and who
FACE_TOPICS: dict[str, FaceTopic] = {
    "scan": FaceTopic(rc.LASER_SCAN, rz.SENSOR_DATA, "lidar_sim"),   # sensor-data QoS
    "odom": FaceTopic(rc.ODOMETRY, rz.RELIABLE_10, "base_driver"),
    "tf": FaceTopic(rc.TF_MESSAGE, TF_QOS, "base_driver"),
    "tf_static": FaceTopic(rc.TF_MESSAGE, rz.LATCHED, "robot_state_publisher"),
    "robot_description": FaceTopic(rc.STRING, rz.LATCHED, "robot_state_publisher"),
    "joint_states": FaceTopic(rc.JOINT_STATE, rz.RELIABLE_10, "base_driver"),
    "clock": FaceTopic(rc.CLOCK, CLOCK_QOS, "base_driver"),
    "map": FaceTopic(rc.OCCUPANCY_GRID, rz.LATCHED, "map_server"),
    "cmd_vel": FaceTopic(rc.TWIST, rz.RELIABLE_10, "planner"),
    "battery": FaceTopic(rc.BATTERY_STATE, rz.RELIABLE_10, "energy_meter"),
    "plan": FaceTopic(rc.PATH, rz.RELIABLE_10, "planner"),
    "markers": FaceTopic(rc.MARKER_ARRAY, rz.RELIABLE_10, "planner"),
    "diagnostics": FaceTopic(rc.DIAGNOSTIC_ARRAY, rz.RELIABLE_10, "diagnostics"),
}
GOAL_TOPIC = FaceTopic(POSE_STAMPED, rz.RELIABLE_10, "planner")   # taken, not published
# our topics the face reads
SUBSCRIBED = ("scan", "odom", "cmd_vel", "battery", "planner/state", "planner/status", "goal",
              "wheels", "clock")


class FaceCore:
    """Turn our messages into (face topic, CDR) pairs; remember what markers and goals need.

    No transport here (the process is :mod:`nodes.ros_face.__main__`). Conversions are
    :mod:`common.ros2_convert`'s (rosbags, ROS 2 Jazzy types); the URDF is
    :mod:`common.urdf`'s. Each ROS topic is presented by the ROS 2 node that stands for the
    stack node it comes from (:data:`FACE_TOPICS`), so ``ros2 node info /papf_planner``
    lists ``/cmd_vel``, ``/plan`` and ``/markers``.

    Frames (REP 105): ``odom`` is the run's world frame, ``base_link`` the robot, ``laser`` the
    LiDAR; ``/tf`` carries odom -> base_link with each odometry sample, ``/tf_static``
    base_link -> laser once, transient local (as ``robot_description``).
    """

    def __init__(self, grid=None) -> None:
        """``grid``: the world's map (:class:`worlds.maps.OccupancyMap`) for ``/map`` and
        ``map -> odom``; None: neither."""
        self.robot_xy: tuple[float, float] | None = None
        self.goal: Goal | None = None          # the run's goal (tolerance, road kept on re-goal)
        self.last_ns = 0
        self.grid = grid
        self.wheels = WheelJoints()
        self.next_battery_ns = 0
        self.next_clock_ns = 0

    def static(self) -> list[tuple[str, bytes]]:
        """What is published once, transient local: the laser mount, the URDF, the map."""
        out = [("tf_static", rc.serialize(rc.tf_static(0), rc.TF_MESSAGE)),
               ("robot_description", rc.serialize(rc.string(rosbot_urdf()), rc.STRING))]
        if self.grid is not None:
            out.append(("map", rc.serialize(rc.occupancy_grid(self.grid), rc.OCCUPANCY_GRID)))
        return out

    def on_message(self, topic: str, msg) -> list[tuple[str, bytes]]:
        """One of our messages -> the (ROS topic, CDR bytes) to publish for it."""
        self.last_ns = max(self.last_ns, getattr(msg, "stamp_ns", 0))
        convert = getattr(self, "_on_" + topic.replace("/", "_"), None)
        return convert(msg) if convert is not None else []

    def _on_scan(self, msg):
        return [("scan", rc.serialize(rc.laser_scan(msg), rc.LASER_SCAN))]

    def _on_odom(self, msg):
        self.robot_xy = (msg.x, msg.y)
        tfs = [rc.tf_odom(msg).transforms[0]]
        if self.grid is not None:
            tfs.append(rc.tf_map_odom(msg.stamp_ns))
        return [("odom", rc.serialize(rc.odometry(msg), rc.ODOMETRY)),
                ("tf", rc.serialize(rc.tf_message(tfs), rc.TF_MESSAGE))]

    def _on_cmd_vel(self, msg):
        return [("cmd_vel", rc.serialize(rc.twist(msg), rc.TWIST))]

    def _on_battery(self, msg):
        if msg.stamp_ns < self.next_battery_ns:
            return []
        self.next_battery_ns = msg.stamp_ns + BATTERY_PERIOD_NS
        return [("battery", rc.serialize(rc.battery_state(msg), rc.BATTERY_STATE))]

    def _on_planner_state(self, msg):
        return [("plan", rc.serialize(rc.path(msg), rc.PATH)),
                ("markers", rc.serialize(rc.markers(msg, self.robot_xy), rc.MARKER_ARRAY))]

    def _on_goal(self, msg):
        if not getattr(msg, "cancel", False):
            self.goal = msg
        return []

    def _on_clock(self, msg):
        if msg.stamp_ns < self.next_clock_ns:
            return []
        self.next_clock_ns = msg.stamp_ns + CLOCK_PERIOD_NS
        return [("clock", rc.serialize(rc.clock(msg.stamp_ns), rc.CLOCK))]

    def _on_wheels(self, msg):
        """Wheel speeds -> ``/joint_states`` (angles integrated) and the wheels' ``/tf``."""
        js, tfs = self.wheels.update(msg)
        return [("joint_states", rc.serialize(js, rc.JOINT_STATE)),
                ("tf", rc.serialize(rc.tf_message(tfs), rc.TF_MESSAGE))]

    def goal_from_pose(self, data: bytes) -> Goal:
        """A ``/goal_pose`` (PoseStamped CDR, RViz's "2D Goal Pose") -> our Goal; SchemaError if
        it is not one, not finite, or in a frame other than ``odom``."""
        try:
            msg = rc.deserialize(data, POSE_STAMPED)
        except Exception as exc:  # rosbags raises struct/index errors on garbage
            raise SchemaError(f"/goal_pose: {len(data)} bytes are not a CDR PoseStamped "
                              f"({type(exc).__name__})") from None
        frame = msg.header.frame_id
        if frame not in GOAL_FRAMES:
            raise SchemaError(f"/goal_pose in frame {frame!r}: give it in 'odom' or 'map' (RViz's "
                              "fixed frame; both are the run's world frame)")
        x, y = float(msg.pose.position.x), float(msg.pose.position.y)
        if not (math.isfinite(x) and math.isfinite(y)):
            raise SchemaError(f"/goal_pose at ({x!r}, {y!r}) is not finite")
        if self.goal is not None:   # keeps the tolerance and the road of the run's goal
            return dataclasses.replace(self.goal, stamp_ns=self.last_ns, x=x, y=y, auth="")
        return Goal(stamp_ns=self.last_ns, x=x, y=y)
