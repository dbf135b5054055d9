"""Every message of the stack, defined once (docs/architecture.md "Messages").

Conventions: time is integer nanoseconds of *sim time* in sim runs (``stamp_ns``);
lengths in metres, angles in radians, speeds in m/s and rad/s. Poses are in the
world file's frame (z up, yaw counter-clockwise from +x); the sim starts the robot at
the world's ``[robot].start`` (plus seeded jitter), not at an odometry origin.
"""

from __future__ import annotations

import numpy as np

from schemas.base import Floats, Message, Points, Strs, field, message
from schemas.planner_state import DEBUG_KINDS, DebugValue, PlannerState, PlannerStateV1

WHEEL_NAMES = ("front_left", "front_right", "rear_left", "rear_right")


@message("Scan", 1)
class Scan(Message):
    """A planar 360° laser scan in the sensor frame (like sensor_msgs/LaserScan).

    ``ranges[i]`` is measured at angle ``angle_min + i * angle_increment`` (CCW from
    the sensor's x axis). ``inf`` = no return within ``range_max``; ``nan`` = invalid
    reading. The sensor sits at (sensor_x, sensor_y, sensor_yaw) in the robot frame.
    """

    stamp_ns: int = field(unit="ns", doc="sim time the scan describes")
    angle_min: float = field(unit="rad")
    angle_increment: float = field(unit="rad")
    range_min: float = field(unit="m")
    range_max: float = field(unit="m")
    ranges: np.ndarray = field(unit="m", doc="float32 ranges; inf = no return, nan = invalid")
    sensor_x: float = field(0.0, unit="m", doc="sensor offset in the robot frame")
    sensor_y: float = field(0.0, unit="m")
    sensor_yaw: float = field(0.0, unit="rad")


@message("Odometry", 1)
class Odometry(Message):
    """Planar pose and body velocities (nav_msgs/Odometry reduced to 2-D)."""

    stamp_ns: int = field(unit="ns")
    x: float = field(unit="m")
    y: float = field(unit="m")
    yaw: float = field(unit="rad")
    v: float = field(unit="m/s", doc="forward speed")
    w: float = field(unit="rad/s", doc="yaw rate")


@message("Twist", 1)
class Twist(Message):
    """A velocity command (geometry_msgs/Twist: linear.x, angular.z).

    ``stamp_ns`` is the stamp of the scan the command answers (lockstep key).

    On a real link the planner adds its short plan (docs/link-driving.md): ``plan`` holds
    poses ``x0, y0, yaw0, x1, y1, yaw1, ...`` (world frame) the robot is meant to be at,
    at ``stamp_ns + k * plan_dt_ns``; pose 0 is the one the command was computed for. The
    robot side follows the plan with its own odometry while it is valid. Empty (the
    default, and always in lockstep): a plain command.
    """

    stamp_ns: int = field(unit="ns")
    v: float = field(unit="m/s")
    w: float = field(unit="rad/s")
    plan: Floats = field((), unit="m, m, rad", doc="poses (x, y, yaw) at stamp + k * plan_dt_ns; "
                                                   "() = a plain command")
    plan_dt_ns: int = field(0, unit="ns", doc="time between the plan's poses; 0 = no plan")


@message("WheelStates", 1)
class WheelStates(Message):
    """Per-wheel speed and motor torque, ordered as ``names``."""

    stamp_ns: int = field(unit="ns")
    speed: Floats = field(unit="rad/s")
    torque: Floats = field(unit="N*m", doc="torque the motor applies to the wheel")
    names: Strs = field(WHEEL_NAMES)


@message("BatteryState", 1)
class BatteryState(Message):
    """Battery pack state as metered (emulated or measured)."""

    stamp_ns: int = field(unit="ns")
    voltage: float = field(unit="V")
    current: float = field(unit="A", doc="drawn from the pack (positive = discharge)")
    power: float = field(unit="W")
    charge_used_mAh: float = field(unit="mAh", doc="since the meter started")
    energy_J: float = field(unit="J", doc="since the meter started")
    soc: float = field(1.0, doc="state of charge 0..1")
    model: str = field("motor", doc="energy model that produced the figures")


@message("BatteryVoltage", 1)
class BatteryVoltage(Message):
    """Pack voltage measured by the robot (sensor_msgs/BatteryState.voltage via the bridge)."""

    stamp_ns: int = field(unit="ns", doc="run time it was received")
    voltage: float = field(unit="V")
    source: str = field("robot", doc="who measured it")


@message("Goal", 1)
class Goal(Message):
    """The global goal position in the world frame, and the road the run is on, if any.

    The road fields describe the world's ``[road]`` (a straight one-way road along +x,
    ``road_lanes`` lanes of ``road_lane_width`` stacked towards +y from the right edge
    ``road_y_min``); ``road_lanes = 0`` means no road. They were added with defaults, so
    goals recorded before them still decode (as "no road").
    """

    stamp_ns: int = field(unit="ns")
    x: float = field(unit="m")
    y: float = field(unit="m")
    tolerance: float = field(0.1, unit="m")
    road_lanes: int = field(0, doc="number of lanes; 0 = no road")
    road_y_min: float = field(0.0, unit="m", doc="right road edge (solid line)")
    road_lane_width: float = field(0.0, unit="m", doc="lane width d_w")
    auth: str = field("", doc="the run's tag (common.runauth): a planner started by a run "
                              "acts only on goals that carry it")
    cancel: bool = field(False, doc="drop the goal: the planner stops (zero commands) and "
                                    "idles until the next goal (a ROS 2 action's cancel)")


PLANNER_STATES = ("idle", "ready", "driving", "reached", "stagnated", "failed")


@message("PlannerStatus", 1)
class PlannerStatus(Message):
    """The planner's progress towards the goal."""

    stamp_ns: int = field(unit="ns")
    state: str = field(choices=PLANNER_STATES)
    reason: str = field("")
    distance_to_goal: float = field(float("nan"), unit="m", nonfinite=True)
    auth: str = field("", doc="the run's tag (common.runauth): the launcher acts only on "
                              "statuses that carry it")


@message("Clock", 1)
class Clock(Message):
    """Sim time, published by the simulated base driver."""

    stamp_ns: int = field(unit="ns")


EVENT_KINDS = ("run_started", "run_ended", "goal_reached", "collision", "timeout",
               "stagnated", "node_fault", "watchdog_stop", "info", "recording_closed",
               "link_lost", "link_restored", "command_refused")


@message("Event", 1)
class Event(Message):
    """Something that happened during a run."""

    stamp_ns: int = field(unit="ns")
    kind: str = field(choices=EVENT_KINDS)
    source: str = field(doc="node that reports it")
    detail: str = field("")
    x: float = field(float("nan"), unit="m", nonfinite=True, doc="where, if known")
    y: float = field(float("nan"), unit="m", nonfinite=True)


LINK_SIDES = ("robot", "laptop")


@message("LinkHealth", 1)
class LinkHealth(Message):
    """How the robot-laptop link behaves, as one side measures it (docs/link-driving.md).

    The robot side measures the round trip of its control loop with its own clock: a
    command's age when it arrives (robot run time minus the stamp of the scan it answers).
    Counts are since the run started; an outage is a silence longer than the watchdog.
    """

    stamp_ns: int = field(unit="ns", doc="run time of the report")
    side: str = field(choices=LINK_SIDES)
    state: str = field("up", choices=("up", "lost"))
    rtt_last_ms: float = field(float("nan"), unit="ms", nonfinite=True,
                               doc="age of the last command at arrival; nan = none yet")
    rtt_p50_ms: float = field(float("nan"), unit="ms", nonfinite=True)
    rtt_p99_ms: float = field(float("nan"), unit="ms", nonfinite=True)
    commands: int = field(0, doc="commands received")
    obeyed: int = field(0, doc="commands taken as the plan to follow")
    late: int = field(0, doc="commands refused: older than their validity when they came")
    stale: int = field(0, doc="commands refused: older than the plan already followed")
    outages: int = field(0, doc="silences longer than the watchdog")
    outage_s: float = field(0.0, unit="s", doc="total length of the outages (the current one too)")
    longest_outage_s: float = field(0.0, unit="s")
    speed_scale: float = field(1.0, doc="speed factor the plan's age allows now (1 = full)")
    monitor_stops: int = field(0, doc="control ticks the collision monitor stopped or slowed")
    held_s: float = field(0.0, unit="s", doc="run time the base was held still for want of a "
                                             "usable command (watchdog, a plan run out)")


@message("ObjectTrack", 1)
class ObjectTrack(Message):
    """One obstacle seen around the robot (an element of :class:`Objects`), world frame."""

    id: int = field(doc="track id, stable while the object is tracked")
    x: float = field(unit="m", doc="centre")
    y: float = field(unit="m")
    yaw: float = field(0.0, unit="rad", doc="heading (direction of travel)")
    vx: float = field(0.0, unit="m/s")
    vy: float = field(0.0, unit="m/s")
    length: float = field(0.0, unit="m", doc="extent along the heading")
    width: float = field(0.0, unit="m", doc="extent across the heading")


OBJECT_SOURCES = ("truth", "tracker")


@message("Objects", 1)
class Objects(Message):
    """The obstacles around the robot at one instant: from the sim's ground truth or a tracker."""

    stamp_ns: int = field(unit="ns", doc="the scan instant they belong to")
    source: str = field(choices=OBJECT_SOURCES)
    tracks: tuple[ObjectTrack, ...] = field(())


@message("Bodies", 1)
class Bodies(Message):
    """The other movers a robot's LiDAR sees at one scan instant (sim; fleets and people).

    The other robots of the fleet (their chassis boxes, at their ground-truth poses) and the
    people (circles), all in the world frame. The sim driver puts it on each robot's
    ``sim/bodies`` just before that robot's ``sim/pose`` of the same scan instant.
    """

    stamp_ns: int = field(unit="ns", doc="the scan instant they belong to")
    robots: Strs = field((), doc="names (namespaces) of the other robots")
    robot_x: Floats = field((), unit="m")
    robot_y: Floats = field((), unit="m")
    robot_yaw: Floats = field((), unit="rad")
    person_x: Floats = field((), unit="m")
    person_y: Floats = field((), unit="m")
    person_radius: Floats = field((), unit="m")
    robot_vx: Floats = field((), unit="m/s", doc="world frame; () in recordings made before")
    robot_vy: Floats = field((), unit="m/s")
    person_vx: Floats = field((), unit="m/s", doc="world frame; () in recordings made before")
    person_vy: Floats = field((), unit="m/s")


@message("People", 1)
class People(Message):
    """Where the world's people (``[[people]]``) are and go at one instant (sim ground truth).

    Index ``i`` is the i-th ``[[people]]`` of the world file, in every message of a run.
    """

    stamp_ns: int = field(unit="ns")
    x: Floats = field((), unit="m")
    y: Floats = field((), unit="m")
    vx: Floats = field((), unit="m/s")
    vy: Floats = field((), unit="m/s")
    radius: Floats = field((), unit="m", doc="body radius")


ALL_MESSAGES: tuple[type[Message], ...] = (
    Scan, Odometry, Twist, WheelStates, BatteryState, BatteryVoltage, Goal, PlannerState,
    PlannerStatus, Clock, Event, Objects, Bodies, People, LinkHealth,
)
#: type name -> the class that decodes it; older versions decode into the current class
#: (a recording made before still reads: schemas/planner_state.py)
BY_TYPE: dict[str, type[Message]] = {m.TYPE: m for m in (*ALL_MESSAGES, PlannerStateV1)}

__all__ = [m.__name__ for m in ALL_MESSAGES] + [
    "ObjectTrack", "DebugValue", "DEBUG_KINDS", "OBJECT_SOURCES", "ALL_MESSAGES", "BY_TYPE", "EVENT_KINDS", "LINK_SIDES", "PLANNER_STATES", "WHEEL_NAMES", "Points",
]
