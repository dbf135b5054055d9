"""Our recorded messages as the ROS 2 face's topics, for a rosbag2 (pure: no files, no bus).

:class:`BagTopics` turns one of our messages on a key (``<ns>/<topic>``) into the ROS 2
messages a rosbag2 of the face holds, stamped on one clock. Shared by ``papf export ros2``
(:mod:`papf.recording.ros2_export`) and the recorder's ``--format ros2``
(:mod:`nodes.recorder.ros2_bag`), so a bag written live and one exported later are the same.

Topics (types: :data:`TOPIC_TYPES`): ``/scan``, ``/odom``, ``/tf`` (odom -> base_link, the
wheels, map -> odom with a map), ``/tf_static``, ``/robot_description``, ``/joint_states``,
``/clock``, ``/map``, ``/cmd_vel``, ``/battery``, ``/plan``, ``/markers``. With several robots
(namespaces) the topics are ``/<robot>/scan``… and the robot's frames ``<robot>/base_link``…;
``odom`` and ``map`` are the world frames all share.

Time: every stamp (bag time, headers, ``/clock``) is ours plus ``offset_ns``: the wall-clock
moment the run's time 0 happened (first message's receive time minus its stamp). A bag so
starts at the real time of its run, and what ROS calls sim time stays consistent: ``ros2
bag play --clock`` republishes the bag's time as ``/clock``, which is the recorded ``/clock``,
and each header is on that clock. Durations are the run's (in a lockstep sim run, sim time:
faster than the wall).
"""

from __future__ import annotations

import dataclasses
import math

from rosbags.interfaces import (
    Qos,
    QosDurability,
    QosHistory,
    QosLiveliness,
    QosReliability,
    QosTime,
)

from common import ros2_convert as rc
from common.units import NS_PER_S
from common.urdf import BASE_LINK, LASER, WHEELS, rosbot_urdf, wheel_origin
from schemas.keys import TOPICS
from schemas.messages import (
    BatteryState,
    Clock,
    Odometry,
    PlannerState,
    Scan,
    Twist,
    WheelStates,
)

_NEVER = QosTime(sec=0, nsec=0)
LATCHED = Qos(history=QosHistory.KEEP_LAST, depth=1, reliability=QosReliability.RELIABLE,
              durability=QosDurability.TRANSIENT_LOCAL, deadline=_NEVER, lifespan=_NEVER,
              liveliness=QosLiveliness.AUTOMATIC, liveliness_lease_duration=_NEVER,
              avoid_ros_namespace_conventions=False)
TOPIC_TYPES = {"scan": rc.LASER_SCAN, "odom": rc.ODOMETRY, "tf": rc.TF_MESSAGE,
               "tf_static": rc.TF_MESSAGE, "robot_description": rc.STRING, "cmd_vel": rc.TWIST,
               "battery": rc.BATTERY_STATE, "plan": rc.PATH, "markers": rc.MARKER_ARRAY,
               "joint_states": rc.JOINT_STATE, "clock": rc.CLOCK, "map": rc.OCCUPANCY_GRID}
LATCHED_TOPICS = ("tf_static", "robot_description", "map")
WHEEL_JOINTS = tuple(f"{name}_wheel_joint" for name in WHEELS)


def split_key(key: str) -> tuple[str, str] | None:
    """``rosbot/planner/state`` -> (``rosbot``, ``planner/state``) (longest stack-topic
    suffix, namespace at least one chunk), else None."""
    parts = key.split("/")
    for i in range(1, len(parts)):
        suffix = "/".join(parts[i:])
        if suffix in TOPICS:
            return "/".join(parts[:i]), suffix
    return None


class WheelJoints:
    """Wheel angles integrated from our wheel speeds -> ``/joint_states`` and the wheels'
    transforms (what robot_state_publisher makes of them: RViz turns the URDF's wheels)."""

    def __init__(self) -> None:
        self.angle = dict.fromkeys(WHEELS, 0.0)   # [rad]
        self.last_ns: int | None = None

    def update(self, msg: WheelStates, frame_prefix: str = ""):
        """(sensor_msgs/JointState, [TransformStamped base_link -> <wheel>_wheel_link])."""
        dt = 0.0 if self.last_ns is None else max(msg.stamp_ns - self.last_ns, 0) / NS_PER_S
        self.last_ns = msg.stamp_ns
        speed = dict(zip(msg.names, (float(v) for v in msg.speed), strict=False))
        torque = dict(zip(msg.names, (float(v) for v in msg.torque), strict=False))
        for name in WHEELS:
            w = speed.get(name, 0.0)
            if math.isfinite(w):
                self.angle[name] = math.remainder(self.angle[name] + w * dt, math.tau)
        js = rc.joint_state(msg.stamp_ns, [frame_prefix + j for j in WHEEL_JOINTS],
                            [self.angle[n] for n in WHEELS], [speed.get(n, 0.0) for n in WHEELS],
                            [torque.get(n, 0.0) for n in WHEELS])
        tfs = rc.wheel_transforms(msg.stamp_ns, {
            f"{frame_prefix}{n}_wheel_link": (wheel_origin(n), self.angle[n]) for n in WHEELS})
        if frame_prefix:
            for tf in tfs:
                tf.header.frame_id = frame_prefix + BASE_LINK
        return js, tfs


class _Robot:
    """One namespace's topic names, frames, wheels and latest pose."""

    def __init__(self, ns: str, several: bool):
        self.prefix = f"/{ns}" if several else ""
        self.frame_prefix = f"{ns}/" if several else ""
        self.xy: tuple[float, float] | None = None
        self.wheels = WheelJoints()

    def frames(self, msg):
        """``msg`` with base_link / laser renamed to this robot's frames (several robots)."""
        if not self.frame_prefix:
            return msg
        for holder in _frame_holders(msg):
            for attr in ("frame_id", "child_frame_id"):
                value = getattr(holder, attr, None)
                if value in (BASE_LINK, LASER):
                    setattr(holder, attr, self.frame_prefix + value)
        return msg


def _frame_holders(msg) -> list:
    out = [msg]
    if hasattr(msg, "header"):
        out.append(msg.header)
    for tf in getattr(msg, "transforms", ()):
        out += [tf, tf.header]
    return out


class BagTopics:
    """Our messages -> (ROS topic, ROS type, ROS message, bag time [ns]) for a rosbag2.

    ``namespaces``: the robots of the recording (one: plain topic names); ``grid``: the
    world's map for ``/map`` and map -> odom (None: neither); ``offset_ns``: added to every
    stamp (module doc)."""

    def __init__(self, namespaces, grid=None, offset_ns: int = 0):
        namespaces = list(namespaces)
        self.robots = {ns: _Robot(ns, len(namespaces) > 1) for ns in namespaces}
        self.grid, self.offset_ns = grid, int(offset_ns)

    def connections(self):
        """(ROS topic, type, latched) of every topic the bag holds."""
        shared = {"clock", "map"} if len(self.robots) > 1 else set()
        out = [(f"/{name}", TOPIC_TYPES[name], name in LATCHED_TOPICS) for name in sorted(shared)
               if name != "map" or self.grid is not None]
        for robot in self.robots.values():
            out += [(f"{robot.prefix}/{name}", typename, name in LATCHED_TOPICS)
                    for name, typename in TOPIC_TYPES.items()
                    if name not in shared and (name != "map" or self.grid is not None)]
        return out

    def static(self, stamp_ns: int) -> list[tuple[str, str, object, int]]:
        """What a bag holds once, at its start: the URDF, the laser mount, the map."""
        t = stamp_ns + self.offset_ns
        out, seen_map = [], False
        for robot in self.robots.values():
            out.append((f"{robot.prefix}/robot_description", rc.STRING, rc.string(rosbot_urdf()), t))
            out.append((f"{robot.prefix}/tf_static", rc.TF_MESSAGE, robot.frames(rc.tf_static(t)), t))
            if self.grid is not None and not seen_map:
                name = "/map" if len(self.robots) > 1 else f"{robot.prefix}/map"
                out.append((name, rc.OCCUPANCY_GRID, rc.occupancy_grid(self.grid, t), t))
                seen_map = True
        return out

    def convert(self, key: str, msg) -> list[tuple[str, str, object, int]]:
        """One of our messages on ``key`` -> its ROS 2 messages (none for what the face
        does not show)."""
        split = split_key(key)
        if split is None or split[0] not in self.robots or not hasattr(msg, "stamp_ns"):
            return []
        robot, topic = self.robots[split[0]], split[1]
        shifted = dataclasses.replace(msg, stamp_ns=msg.stamp_ns + self.offset_ns)
        return [(_name(robot, name, len(self.robots)), TOPIC_TYPES[name], robot.frames(m),
                 shifted.stamp_ns) for name, m in self._ros(robot, topic, shifted)]

    def _ros(self, robot: _Robot, topic: str, msg) -> list[tuple[str, object]]:
        if topic == "scan" and isinstance(msg, Scan):
            return [("scan", rc.laser_scan(msg))]
        if topic == "odom" and isinstance(msg, Odometry):
            robot.xy = (msg.x, msg.y)
            tfs = [rc.tf_odom(msg).transforms[0]]
            if self.grid is not None:
                tfs.append(rc.tf_map_odom(msg.stamp_ns))
            return [("odom", rc.odometry(msg)), ("tf", rc.tf_message(tfs))]
        if topic == "cmd_vel" and isinstance(msg, Twist):
            return [("cmd_vel", rc.twist(msg))]
        if topic == "battery" and isinstance(msg, BatteryState):
            return [("battery", rc.battery_state(msg))]
        if topic == "planner/state" and isinstance(msg, PlannerState):
            return [("plan", rc.path(msg)), ("markers", rc.markers(msg, robot.xy))]
        if topic == "wheels" and isinstance(msg, WheelStates):
            js, tfs = robot.wheels.update(msg)
            return [("joint_states", js), ("tf", rc.tf_message(tfs))]
        if topic == "clock" and isinstance(msg, Clock):
            return [("clock", rc.clock(msg.stamp_ns))]
        return []


def _name(robot: _Robot, name: str, robots: int) -> str:
    if robots > 1 and name in ("clock", "map"):
        return f"/{name}"
    return f"{robot.prefix}/{name}"
