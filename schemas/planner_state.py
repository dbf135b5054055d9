"""The planner's debug message: what every planner shows, and each plug-in's own output generically.

``PlannerState`` (v2) names only what every planner has (force, mode, heading and speed
references, temporary goal, predicted path, obstacles used, compute time); a plug-in's own
output travels in ``debug``: one :class:`DebugValue` per field the plug-in declares, carrying
its kind, unit and drawing style, so a viewer, the ROS 2 face's markers, the pictures and the
report draw a planner they have never heard of (docs/architecture.md "Extending").

Version 1 named PAPF's, AR-APF's and IAPF's fields in the message itself; a v1 message (an
older recording) decodes into v2 (:class:`PlannerStateV1`, :func:`upgrade`).
"""

from __future__ import annotations

import math

from common.errors import SchemaError
from schemas.base import Floats, Message, Paths, Points, field, message

#: what a debug value is, and the one payload field each kind fills
DEBUG_KINDS = ("points", "paths", "point", "scalar", "count")
PAYLOAD = {"points": "points", "point": "points", "paths": "paths", "scalar": "value",
           "count": "value"}
GREY = (0.5, 0.5, 0.5, 1.0)


@message("DebugValue", 1)
class DebugValue(Message):
    """One debug field a planner plug-in declares, with this cycle's value (world frame).

    The payload by ``kind``: ``points`` and ``point`` (0 or 1 point: none or one) in
    ``points``; ``paths`` (polylines) in ``paths``; ``scalar`` (nan = none) and ``count``
    (a whole number) in ``value``. The other payload fields stay empty. ``colour``,
    ``size`` and ``dashed`` are the plug-in's drawing style.
    """

    name: str = field(doc="the plug-in's name of the field, e.g. top_quarks")
    kind: str = field(choices=DEBUG_KINDS)
    unit: str = field("", doc="unit of the values, e.g. m")
    label: str = field("", doc="words for legends and captions; '' = the name")
    colour: Floats = field(GREY, doc="r, g, b, a in 0..1", length=4)
    size: float = field(0.05, unit="m", doc="drawn size: line thickness or marker diameter")
    dashed: bool = field(False, doc="lines drawn dashed")
    points: Points = field((), doc="kind points, or point (at most one)")
    paths: Paths = field((), doc="kind paths: polylines")
    value: float = field(math.nan, nonfinite=True, doc="kind scalar (nan = none) or count")

    @property
    def caption(self) -> str:
        """Its words in legends: the label, else the name."""
        return self.label or self.name.replace("_", " ")

    def words(self) -> str:
        """A scalar or count as words beside a picture: ``label value unit``."""
        value = f"{int(self.value)}" if self.kind == "count" else f"{self.value:.3g}"
        return f"{self.caption} {value}{' ' + self.unit if self.unit else ''}"

    @classmethod
    def from_wire(cls, wire):
        """Decode and check that the payload is the kind's (a wrong one: SchemaError)."""
        msg = super().from_wire(wire)
        problem = payload_problem(msg)
        if problem:
            raise SchemaError(f"{cls.TYPE}: {msg.name!r}: {problem}")
        return msg


def payload_problem(v: DebugValue) -> str:
    """What is wrong with ``v``'s payload for its kind and style ('' = nothing)."""
    own = PAYLOAD[v.kind]
    if own != "points" and v.points or own != "paths" and v.paths or (
            own != "value" and not math.isnan(v.value)):
        return f"kind {v.kind} carries its value in {own!r} only"
    if v.kind == "point" and len(v.points) > 1:
        return f"kind point holds at most one point, got {len(v.points)}"
    if v.kind == "count" and not (math.isfinite(v.value) and v.value == int(v.value)):
        return f"kind count holds a whole number, got {v.value!r}"
    if not all(0.0 <= c <= 1.0 for c in v.colour):
        return f"colour components must be in 0..1, got {v.colour}"
    if not (0.0 < v.size < 100.0):
        return f"size must be in (0, 100) m, got {v.size!r}"
    return ""


@message("PlannerState", 2)
class PlannerState(Message):
    """What the planner computed this cycle (what the papers drew in RViz)."""

    stamp_ns: int = field(unit="ns")
    algorithm: str = field(doc="planner name, e.g. apf, papf")
    mode: str = field("drive", doc="planner-specific mode, e.g. drive, bypass, stop")
    force: Floats = field((0.0, 0.0), unit="N (APF units)", doc="resultant force F_w, world frame",
                          length=2)
    heading_ref: float = field(0.0, unit="rad", doc="reference orientation theta*")
    v_ref: float = field(0.0, unit="m/s")
    w_ref: float = field(0.0, unit="rad/s")
    temporary_goal: Floats = field((), unit="m", doc="[x, y] or empty")
    predicted_path: Points = field((), unit="m")
    obstacle_count: int = field(0, doc="obstacles used this cycle: scan points, or the tracks "
                                       "of a planner that plans on tracks")
    v_target: float = field(0.0, unit="m/s", doc="speed the planner aims at (its own speed "
                                                 "law's, else the command's)")
    compute_ns: int = field(0, unit="ns", doc="wall time the cycle took (not deterministic)")
    debug: tuple[DebugValue, ...] = field((), doc="the plug-in's own declared output")

    def value(self, name: str) -> DebugValue | None:
        """The debug value called ``name``, or None."""
        return next((d for d in self.debug if d.name == name), None)

    def get(self, name: str, default=None):
        """The payload of debug value ``name`` (its points, paths or number, by its kind), or
        ``default`` when the planner declares no such field."""
        d = self.value(name)
        return default if d is None else getattr(d, PAYLOAD[d.kind])


@message("PlannerState", 1)
class PlannerStateV1(Message):
    """PlannerState as recorded before v2: decodes into a v2 :class:`PlannerState`."""

    stamp_ns: int = field(unit="ns")
    algorithm: str = field()
    mode: str = field("drive")
    force: Floats = field((0.0, 0.0), length=2)
    heading_ref: float = field(0.0)
    v_ref: float = field(0.0)
    w_ref: float = field(0.0)
    temporary_goal: Floats = field(())
    predicted_path: Points = field(())
    abandoned_paths: Paths = field(())
    top_quarks: Points = field(())
    virtual_walls: Paths = field(())
    virtual_obstacles: Points = field(())
    obstacle_count: int = field(0)
    local_minimum_count: int = field(0)
    lane_goal_y: float = field(float("nan"), nonfinite=True)
    v_target: float = field(0.0)
    compute_ns: int = field(0)

    @classmethod
    def from_wire(cls, wire):
        """The v1 map, checked as v1, as a v2 :class:`PlannerState`."""
        return upgrade(super().from_wire(wire))


#: v1's named fields as the planners that wrote them declare them now: name -> (kind, unit,
#: label, colour, size, dashed, algorithm that owned it). History: v1 is never written again.
V1_FIELDS = {
    "abandoned_paths": ("paths", "m", "abandoned prediction", (0.5, 0.5, 0.5, 0.5), 0.015, True,
                        "papf"),
    "top_quarks": ("points", "m", "top quark", (0.84, 0.15, 0.16, 0.9), 0.12, False, "papf"),
    "virtual_walls": ("paths", "m", "virtual wall", (0.89, 0.47, 0.76, 1.0), 0.05, False,
                      "arapf"),
    "virtual_obstacles": ("points", "m", "virtual obstacle", (0.89, 0.47, 0.76, 0.9), 0.1,
                          False, "arapf"),
    "local_minimum_count": ("count", "", "local minima ahead", GREY, 0.05, False, "iapf"),
    "lane_goal_y": ("scalar", "m", "lane goal y", (0.09, 0.75, 0.81, 1.0), 0.05, False, "iapf"),
}


def upgrade(old: PlannerStateV1) -> PlannerState:
    """A v1 state as v2: its generic fields as they were, its named fields as debug values
    (those of the planner that owned them, and any other one that is not empty)."""
    debug = []
    for name, (kind, unit, label, colour, size, dashed, owner) in V1_FIELDS.items():
        value = getattr(old, name)
        empty = (value == 0 if kind == "count" else math.isnan(value) if kind == "scalar"
                 else not value)
        if empty and old.algorithm != owner:
            continue
        payload = {PAYLOAD[kind]: float(value) if PAYLOAD[kind] == "value" else value}
        debug.append(DebugValue(name=name, kind=kind, unit=unit, label=label, colour=colour,
                                size=size, dashed=dashed, **payload))
    return PlannerState(
        stamp_ns=old.stamp_ns, algorithm=old.algorithm, mode=old.mode, force=old.force,
        heading_ref=old.heading_ref, v_ref=old.v_ref, w_ref=old.w_ref,
        temporary_goal=old.temporary_goal, predicted_path=old.predicted_path,
        obstacle_count=old.obstacle_count, v_target=old.v_target, compute_ns=old.compute_ns,
        debug=tuple(debug))
