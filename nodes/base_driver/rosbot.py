"""The real ROSbot as seen through ``zenoh-bridge-ros2dds``: our messages <-> its CDR (pure).

No transport here (the process is :mod:`nodes.base_driver.rosbot_node`). docs/architecture.md "The robot":
the robot takes ``geometry_msgs/Twist`` on ``cmd_vel`` (linear.x, angular.z), publishes
``nav_msgs/Odometry`` on ``odometry/filtered`` (EKF of wheels + IMU) and
``sensor_msgs/BatteryState`` on ``battery`` (voltage only). The bridge maps topic ``/t``
to key ``t`` (``<bridge-ns>/t`` with a bridge namespace); payloads are CDR with the
4-byte encapsulation header, coded with ``rosbags`` (:mod:`common.ros2`).

Wheels: the ROSbot reports no wheel torque, so :func:`wheel_states` derives them from
two odometry samples — speeds from skid-steer kinematics, torques from a rigid-body
estimate (mass x acceleration, yaw inertia x angular acceleration, shared equally by
the two wheels of a side; rolling and skid friction are NOT included). The ``paper``
energy model (eq. 6, odometry only) is therefore the one to use on real data.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from common import robot, ros2
from schemas import Odometry, WheelStates
from schemas.messages import WHEEL_NAMES

WHEEL_RADIUS = robot.WHEEL_RADIUS_M          # [m]
MASS = robot.MASS_KG                         # [kg]
YAW_INERTIA = robot.YAW_INERTIA_KGM2         # [kg m^2]
EFFECTIVE_TRACK = robot.EFFECTIVE_TRACK_M    # [m] (the world simulator reproduces the same)


# -- commands -----------------------------------------------------------------------------------
def twist_to_cdr(v: float, w: float, typename: str = ros2.TWIST, stamp_ns: int = 0) -> bytes:
    """Our command (v [m/s], w [rad/s]) as the CDR the robot takes: ``geometry_msgs/Twist``, or
    ``TwistStamped`` (header stamp ``stamp_ns`` [ns, wall clock], frame ``base_link``)."""
    if typename == ros2.TWIST_STAMPED:
        return ros2.encode(ros2.twist_stamped(v, w, stamp_ns), typename)
    return ros2.encode(ros2.twist(v, w), ros2.TWIST)


def cdr_to_twist(data: bytes, typename: str = ros2.TWIST) -> tuple[float, float]:
    """(linear.x, angular.z) of a CDR ``geometry_msgs/Twist`` (or ``TwistStamped``)."""
    msg = ros2.decode(data, typename)
    tw = msg.twist if typename == ros2.TWIST_STAMPED else msg
    v, w = float(tw.linear.x), float(tw.angular.z)
    if not (math.isfinite(v) and math.isfinite(w)):
        raise ros2.CdrError(f"{typename}: non-finite linear.x {v!r} or angular.z {w!r}")
    return v, w


# -- odometry -----------------------------------------------------------------------------------
class Pose2D(NamedTuple):
    x: float     # [m]
    y: float     # [m]
    yaw: float   # [rad]


ORIGIN = Pose2D(0.0, 0.0, 0.0)


class RobotOdom(NamedTuple):
    """The robot's odometry reduced to 2-D, in the robot's own ``odom`` frame."""

    stamp_ns: int   # ROS header stamp (the robot's clock)
    pose: Pose2D
    v: float        # [m/s] forward speed (twist.linear.x, base_link frame)
    w: float        # [rad/s] yaw rate


def cdr_to_robot_odom(data: bytes) -> RobotOdom:
    msg = ros2.decode(data, ros2.ODOMETRY)
    p, q = msg.pose.pose.position, msg.pose.pose.orientation
    values = (p.x, p.y, q.x, q.y, q.z, q.w, msg.twist.twist.linear.x, msg.twist.twist.angular.z)
    if not all(math.isfinite(x) for x in values):
        raise ros2.CdrError(f"{ros2.ODOMETRY}: non-finite pose or twist {values}")
    return RobotOdom(ros2.stamp_ns(msg.header), Pose2D(float(p.x), float(p.y), ros2.yaw_of(q)),
                     float(msg.twist.twist.linear.x), float(msg.twist.twist.angular.z))


def compose(a: Pose2D, b: Pose2D) -> Pose2D:
    """a ⊕ b: pose b given in frame a, expressed in a's parent frame."""
    c, s = math.cos(a.yaw), math.sin(a.yaw)
    return Pose2D(a.x + c * b.x - s * b.y, a.y + s * b.x + c * b.y, _wrap(a.yaw + b.yaw))


def inverse(a: Pose2D) -> Pose2D:
    c, s = math.cos(a.yaw), math.sin(a.yaw)
    return Pose2D(-c * a.x - s * a.y, s * a.x - c * a.y, _wrap(-a.yaw))


def _wrap(angle: float) -> float:
    return math.atan2(math.sin(angle), math.cos(angle))


class OdomFrame:
    """Re-express the robot's odometry in the run's world frame.

    The robot's ``odom`` frame starts wherever its EKF started; a run's world frame has
    the robot at ``world_start`` when the run starts. :meth:`anchor` takes the robot's
    pose at that moment; :meth:`to_world` maps every later pose: world_start ⊕ (anchor⁻¹ ⊕ p).
    """

    def __init__(self, world_start: Pose2D = ORIGIN):
        self.world_start = world_start
        self._anchor_inv: Pose2D | None = None

    def anchor(self, robot_pose: Pose2D) -> None:
        self._anchor_inv = inverse(robot_pose)

    @property
    def anchored(self) -> bool:
        return self._anchor_inv is not None

    def to_world(self, odom: RobotOdom, stamp_ns: int) -> Odometry:
        rel = compose(self._anchor_inv, odom.pose) if self._anchor_inv else odom.pose
        p = compose(self.world_start, rel)
        return Odometry(stamp_ns=stamp_ns, x=p.x, y=p.y, yaw=p.yaw, v=odom.v, w=odom.w)


# -- battery ------------------------------------------------------------------------------------
def cdr_to_voltage(data: bytes) -> float:
    """Pack voltage [V] of a CDR ``sensor_msgs/BatteryState`` (the ROSbot fills only that)."""
    v = float(ros2.decode(data, ros2.BATTERY_STATE).voltage)
    if not (math.isfinite(v) and v > 0.0):
        raise ros2.CdrError(f"{ros2.BATTERY_STATE}: voltage {v!r} V is not a finite number > 0")
    return v


# -- wheels -------------------------------------------------------------------------------------
def wheel_states(prev: Odometry | None, odom: Odometry) -> WheelStates:
    """Wheel speeds [rad/s] and estimated torques [N m] at ``odom.stamp_ns`` (see module doc).

    Speeds: side speed v ∓ w B/2 over r (B = :data:`EFFECTIVE_TRACK`). Torques: per wheel
    r (m a / 4 ∓ I β / (2 B)), so that the four wheel forces give m a and the yaw moment I β;
    a and β by differencing ``prev`` and ``odom`` (zero for the first sample).
    """
    half = 0.5 * EFFECTIVE_TRACK
    left, right = (odom.v - odom.w * half) / WHEEL_RADIUS, (odom.v + odom.w * half) / WHEEL_RADIUS
    a = beta = 0.0
    if prev is not None and odom.stamp_ns > prev.stamp_ns:
        dt = (odom.stamp_ns - prev.stamp_ns) * 1e-9
        a, beta = (odom.v - prev.v) / dt, (odom.w - prev.w) / dt
    f_common, f_yaw = MASS * a / 4.0, YAW_INERTIA * beta / (2.0 * EFFECTIVE_TRACK)
    tl, tr = WHEEL_RADIUS * (f_common - f_yaw), WHEEL_RADIUS * (f_common + f_yaw)
    # WHEEL_NAMES = front_left, front_right, rear_left, rear_right
    return WheelStates(stamp_ns=odom.stamp_ns, speed=(left, right, left, right),
                       torque=(tl, tr, tl, tr), names=WHEEL_NAMES)
