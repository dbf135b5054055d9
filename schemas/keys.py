"""Zenoh key expressions of one robot namespace, and the message type on each (docs/architecture.md "Transport")."""

from __future__ import annotations

from dataclasses import dataclass

from schemas.messages import (
    BatteryState,
    BatteryVoltage,
    Bodies,
    Clock,
    Event,
    Goal,
    LinkHealth,
    Objects,
    Odometry,
    People,
    PlannerState,
    PlannerStatus,
    Scan,
    Twist,
    WheelStates,
)

# suffix -> message type; the one table of the stack's topics.
TOPICS = {
    "scan": Scan,
    "odom": Odometry,
    "cmd_vel": Twist,
    "wheels": WheelStates,
    "battery": BatteryState,
    "battery/measured": BatteryVoltage,   # the real robot's pack voltage (rosbot driver)
    "goal": Goal,
    "planner/state": PlannerState,
    "planner/status": PlannerStatus,
    "clock": Clock,
    "sim/pose": Odometry,
    "events": Event,
    "objects": Objects,     # obstacle tracks: sim ground truth or the tracker node
    "sim/bodies": Bodies,   # the other robots and the people a robot's LiDAR sees (sim fleets)
    "sim/people": People,   # the world's people, every instant (sim driver)
    "cmd_vel/applied": Twist,   # what the rosbot driver sent to the base (stamp = run time)
    "link": LinkHealth,     # the link's health as the robot (or laptop) side measures it
}

# Topics with one publisher whose stamps never go back within a run (a new run restarts
# sim time at 0): a message older than the last one on them is dropped (common.units.StampGuard).
STAMP_ORDERED = frozenset({"scan", "odom", "wheels", "battery", "battery/measured", "clock",
                           "sim/pose", "sim/people"})


@dataclass(frozen=True)
class Keys:
    """Keys under a namespace: ``Keys("rosbot").scan == "rosbot/scan"``."""

    ns: str = "rosbot"

    def __post_init__(self) -> None:
        ns = self.ns
        if (not ns or ns.startswith("/") or ns.endswith("/") or "//" in ns
                or set(ns) & set("*$?# \t\n") or not ns.isprintable() or len(ns) > 200):
            raise ValueError(f"namespace {ns[:60]!r} must be a plain key like 'rosbot' or "
                             "'lab/r1' (no empty parts, no spaces or control characters, "
                             "no * $ ? #, at most 200 characters)")

    def key(self, suffix: str) -> str:
        """The key of ``suffix`` in this namespace."""
        return f"{self.ns}/{suffix}"

    def alive(self, node: str = "*") -> str:
        """Liveliness token key of a node (``*`` matches all)."""
        return f"{self.ns}/alive/{node}"

    def type_of(self, key: str):
        """Message type carried on a full key of this namespace, or None."""
        prefix = self.ns + "/"
        return TOPICS.get(key[len(prefix):]) if key.startswith(prefix) else None

    scan = property(lambda self: self.key("scan"))
    odom = property(lambda self: self.key("odom"))
    cmd_vel = property(lambda self: self.key("cmd_vel"))
    wheels = property(lambda self: self.key("wheels"))
    battery = property(lambda self: self.key("battery"))
    battery_measured = property(lambda self: self.key("battery/measured"))
    goal = property(lambda self: self.key("goal"))
    planner_state = property(lambda self: self.key("planner/state"))
    planner_status = property(lambda self: self.key("planner/status"))
    clock = property(lambda self: self.key("clock"))
    sim_pose = property(lambda self: self.key("sim/pose"))
    events = property(lambda self: self.key("events"))
    objects = property(lambda self: self.key("objects"))
