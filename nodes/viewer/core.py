"""The viewer's pure core: a namespace's messages in, Foxglove channel messages out.

:data:`CHANNELS` is the one table of what the viewer serves; :class:`ViewCore` turns each
``(topic, message)`` into ``[(channel, json_dict, log_time_ns), ...]``. No Zenoh, sockets
or clocks: used by the viewer node (``__main__``) and ``papf export foxglove``.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from importlib import resources

from nodes.viewer import convert as cv
from nodes.viewer.scene import (
    bodies_scene,
    footprint_scene,
    mind_scene,
    moving_scene,
    objects_scene,
    world_scene,
)
from schemas.messages import (
    BatteryState,
    Bodies,
    Event,
    Goal,
    Objects,
    Odometry,
    PlannerState,
    PlannerStatus,
    Scan,
    Twist,
)
from worlds import World

NS = 1_000_000_000


@dataclass(frozen=True)
class ChannelSpec:
    topic: str          # Foxglove topic
    schema: str         # schema name (foxglove.* = Foxglove's own, papf.* = ours, JSON Schema)
    source: str         # stack topics it is made from (doc)
    rate: str           # when it is published (doc)


CHANNELS: tuple[ChannelSpec, ...] = (
    ChannelSpec("/scan", "foxglove.LaserScan", "scan", "each scan (10 Hz)"),
    ChannelSpec("/tf", "foxglove.FrameTransforms", "sim/pose or odom; scan",
                "world->base_link each pose (50 Hz), base_link->laser each scan"),
    ChannelSpec("/robot/pose", "foxglove.PoseInFrame", "sim/pose or odom", "each pose (50 Hz)"),
    ChannelSpec("/goal", "foxglove.PoseInFrame", "goal", "each goal, repeated with the world"),
    ChannelSpec("/world", "foxglove.SceneUpdate", "world file; robot facts; scan (time)",
                "every second (obstacles, road, start, goal, the robot's footprint); the "
                "moving obstacles with each scan"),
    ChannelSpec("/planner/scene", "foxglove.SceneUpdate", "planner/state (+ pose)",
                "each planner cycle (10 Hz)"),
    ChannelSpec("/objects", "foxglove.SceneUpdate", "objects",
                "each set of obstacle tracks (10 Hz, with --objects truth|tracker)"),
    ChannelSpec("/fleet", "foxglove.SceneUpdate", "sim/bodies",
                "each scan instant (10 Hz) of a fleet or a world with people: the other "
                "robots and the people"),
    ChannelSpec("/log", "foxglove.Log", "events; the viewer's own notes", "as they happen"),
    ChannelSpec("/battery", "papf.BatteryState", "battery", "each sample (50 Hz)"),
    ChannelSpec("/cmd_vel", "papf.Twist", "cmd_vel", "each command (10 Hz)"),
    ChannelSpec("/planner/status", "papf.PlannerStatus", "planner/status", "each cycle (10 Hz)"),
    ChannelSpec("/odom", "papf.Odometry", "odom", "each sample (50 Hz)"),
)
PLOT_TYPES = {"papf.BatteryState": BatteryState, "papf.Twist": Twist,
              "papf.PlannerStatus": PlannerStatus, "papf.Odometry": Odometry}
SUBSCRIBED = ("scan", "odom", "sim/pose", "goal", "planner/state", "planner/status", "cmd_vel",
              "battery", "events", "objects", "sim/bodies")
GOAL_TOPICS = ("/goal_pose", "/move_base_simple/goal", "/clicked_point", "/goal")


def schema_json(name: str) -> dict:
    """The JSON Schema of a channel's schema name (Foxglove's vendored ones, or ours)."""
    if name.startswith("foxglove."):
        text = (resources.files("nodes.viewer") / "foxglove_schemas" / f"{name}.json").read_text()
        return json.loads(text)
    return cv.plot_schema(PLOT_TYPES[name])


class ViewCore:
    """State of one view: the world, the latest pose and goal, which pose source is in use.

    ``repeat_ns``: re-emit the world and goal every so much message time (recordings, so a
    seek finds them); None = only when :meth:`static_outputs` is called (live: the wrapper
    calls it on a wall-clock timer so a client that joins late sees them).

    Pose source: ground truth (``sim/pose``) as soon as one arrives, else odometry — the
    same choice as the run summary's path length.
    """

    def __init__(self, world: World | None = None, repeat_ns: int | None = None):
        self.world, self.repeat_ns = world, repeat_ns
        self.pose_topic: str | None = None
        self.robot_xy: tuple[float, float] | None = None
        self.goal: Goal | None = None
        self.last_ns = 0
        self._last_static_ns: int | None = None
        self._handlers = {"scan": self._scan, "odom": self._odom, "sim/pose": self._pose,
                          "goal": self._goal, "planner/state": self._state,
                          "planner/status": self._plot("/planner/status"),
                          "cmd_vel": self._plot("/cmd_vel"), "battery": self._plot("/battery"),
                          "events": self._event, "objects": self._objects,
                          "sim/bodies": self._bodies}

    def on_message(self, topic: str, msg) -> list[tuple[str, dict, int]]:
        """Foxglove messages for one stack message (unknown topics: none)."""
        handler = self._handlers.get(topic)
        if handler is None:
            return []
        stamp_ns = getattr(msg, "stamp_ns", self.last_ns)
        self.last_ns = max(self.last_ns, stamp_ns)
        out = handler(msg)
        if self.repeat_ns is not None and (self._last_static_ns is None or
                                           self.last_ns - self._last_static_ns >= self.repeat_ns):
            out = self.static_outputs() + out
        return out

    def static_outputs(self) -> list[tuple[str, dict, int]]:
        """The world (and footprint) and the current goal, stamped with the latest time."""
        t = self.last_ns
        self._last_static_ns = t
        out = [("/world", footprint_scene(t), t)]
        if self.world is not None:
            out.insert(0, ("/world", world_scene(self.world, t), t))
        if self.goal is not None:
            out.append(("/goal", cv.pose_in_frame(t, self.goal.x, self.goal.y), t))
        return out

    def note(self, level: int, message: str) -> tuple[str, dict, int]:
        """A line of the viewer's own on ``/log`` (refused goals, parameter errors)."""
        return ("/log", cv.log(self.last_ns, level, "viewer", message), self.last_ns)

    # -- handlers -----------------------------------------------------------------------------
    def _scan(self, scan: Scan):
        t = scan.stamp_ns
        out = [("/tf", cv.laser_transforms(scan), t), ("/scan", cv.laser_scan(scan), t)]
        if self.world is not None and self.world.has_motion:
            out.append(("/world", moving_scene(self.world, t), t))
        return out

    def _odom(self, odom: Odometry):
        out = [("/odom", cv.plot_dict(odom), odom.stamp_ns)]
        if self.pose_topic in (None, "odom"):
            self.pose_topic = "odom"
            out += self._robot(odom)
        return out

    def _pose(self, pose: Odometry):
        self.pose_topic = "sim/pose"
        return self._robot(pose)

    def _robot(self, pose: Odometry):
        self.robot_xy = (pose.x, pose.y)
        t = pose.stamp_ns
        return [("/tf", cv.robot_transforms(pose), t), ("/robot/pose", cv.robot_pose(pose), t)]

    def _goal(self, goal: Goal):
        self.goal = goal
        return [("/goal", cv.goal_pose(goal), goal.stamp_ns)]

    def _state(self, state: PlannerState):
        return [("/planner/scene", mind_scene(state, self.robot_xy), state.stamp_ns)]

    def _objects(self, msg: Objects):
        return [("/objects", objects_scene(msg), msg.stamp_ns)]

    def _bodies(self, msg: Bodies):
        return [("/fleet", bodies_scene(msg), msg.stamp_ns)]

    def _event(self, ev: Event):
        return [("/log", cv.event_log(ev), ev.stamp_ns)]

    def _plot(self, channel: str):
        return lambda msg: [(channel, cv.plot_dict(msg), msg.stamp_ns)]


# -- from the viewer to the stack ------------------------------------------------------------
def goal_from_client(data: bytes) -> tuple[float, float] | None:
    """(x, y) of a pose or point a client published as JSON, or None if it holds none.

    Accepts what Foxglove's 3D panel publishes (``geometry_msgs`` PoseStamped with
    ``pose.position``, PointStamped with ``point``), foxglove.PoseInFrame, and ``{x, y}``.
    """
    try:
        obj = json.loads(bytes(data).decode("utf-8"))
    except (UnicodeDecodeError, ValueError):
        return None
    if not isinstance(obj, dict):
        return None
    for path in (("pose", "position"), ("pose", "pose", "position"), ("point",), ("position",),
                 ()):
        node = obj
        for key in path:
            node = node.get(key) if isinstance(node, dict) else None
        if isinstance(node, dict):
            x, y = node.get("x"), node.get("y")
            if all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
                   for v in (x, y)):
                return float(x), float(y)
    return None


def param_sets(values: dict[str, object]) -> list[str]:
    """Parameters from the Parameters panel -> ``--set`` strings (``name=value``)."""
    out = []
    for name, value in values.items():
        if isinstance(value, bool):
            text = "true" if value else "false"
        elif isinstance(value, float):
            text = repr(value)
        else:
            text = str(value)
        out.append(f"{name}={text}")
    return out
