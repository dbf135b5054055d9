"""Our messages -> Foxglove's well-known messages, as JSON-ready dicts (pure, no I/O).

Every function returns a plain dict that validates against the Foxglove JSON Schema named
in its docstring (``nodes/viewer/foxglove_schemas/``, from ``@foxglove/schemas``); the
tests check each one. Times: our ``stamp_ns`` (sim time in sim runs) becomes Foxglove's
``{sec, nsec}``. Frames: ``world`` (the world file's frame) -> ``base_link`` (the robot)
-> ``laser`` (the scan's sensor pose plus the LiDAR's height).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence

import numpy as np

from common.robot import LIDAR_HEIGHT_M
from schemas.messages import BatteryState, Event, Goal, Odometry, PlannerStatus, Scan, Twist

WORLD, BASE, LASER = "world", "base_link", "laser"
NO_RETURN_M = 0.0   # [m] range sent for a beam with no return (inf) or an invalid one (nan)

# foxglove.LogLevel
LOG_INFO, LOG_WARNING, LOG_ERROR = 2, 3, 4
EVENT_LEVELS = {"collision": LOG_WARNING, "stagnated": LOG_WARNING, "watchdog_stop": LOG_WARNING,
                "timeout": LOG_WARNING, "node_fault": LOG_ERROR}
# foxglove.LineType
LINE_STRIP, LINE_LOOP, LINE_LIST = 0, 1, 2


# -- building blocks -------------------------------------------------------------------------
def stamp(ns: int) -> dict:
    """Integer nanoseconds -> foxglove ``time`` {sec, nsec} (negative stamps clamp to 0)."""
    ns = max(int(ns), 0)
    return {"sec": ns // 1_000_000_000, "nsec": ns % 1_000_000_000}


def vec3(x: float = 0.0, y: float = 0.0, z: float = 0.0) -> dict:
    """A foxglove.Vector3 (components in m or m/s as the caller means)."""
    return {"x": float(x), "y": float(y), "z": float(z)}


def yaw_quat(yaw: float) -> dict:
    """Rotation about +z by ``yaw`` [rad] as a foxglove.Quaternion."""
    return {"x": 0.0, "y": 0.0, "z": math.sin(yaw / 2.0), "w": math.cos(yaw / 2.0)}


def pose(x: float = 0.0, y: float = 0.0, z: float = 0.0, yaw: float = 0.0) -> dict:
    """foxglove.Pose."""
    return {"position": vec3(x, y, z), "orientation": yaw_quat(yaw)}


def colour(r: float, g: float, b: float, a: float = 1.0) -> dict:
    """foxglove.Color, components 0..1."""
    return {"r": float(r), "g": float(g), "b": float(b), "a": float(a)}


def line(points: Iterable[Sequence[float]], rgba: dict, thickness: float = 0.03,
         z: float = 0.02, kind: int = LINE_STRIP) -> dict:
    """foxglove.LinePrimitive through (x, y) points at height ``z``, thickness in metres."""
    return {"type": kind, "pose": pose(), "thickness": float(thickness), "scale_invariant": False,
            "points": [vec3(p[0], p[1], z) for p in points], "color": rgba, "colors": [],
            "indices": []}


def sphere(x: float, y: float, z: float, diameter: float, rgba: dict) -> dict:
    """foxglove.SpherePrimitive."""
    return {"pose": pose(x, y, z), "size": vec3(diameter, diameter, diameter), "color": rgba}


def cube(x: float, y: float, z: float, yaw: float, size: Sequence[float], rgba: dict) -> dict:
    """foxglove.CubePrimitive centred at (x, y, z)."""
    return {"pose": pose(x, y, z, yaw), "size": vec3(*size), "color": rgba}


def cylinder(x: float, y: float, z: float, radius: float, height: float, rgba: dict) -> dict:
    """foxglove.CylinderPrimitive centred at (x, y, z), axis z."""
    return {"pose": pose(x, y, z), "size": vec3(2 * radius, 2 * radius, height),
            "bottom_scale": 1.0, "top_scale": 1.0, "color": rgba}


def arrow(x: float, y: float, z: float, yaw: float, length: float, rgba: dict) -> dict:
    """foxglove.ArrowPrimitive from (x, y, z) along ``yaw``, ``length`` [m] overall."""
    head = min(0.12, 0.4 * length)
    return {"pose": pose(x, y, z, yaw), "shaft_length": max(length - head, 0.0),
            "shaft_diameter": 0.03, "head_length": head, "head_diameter": 0.08, "color": rgba}


def text(x: float, y: float, z: float, words: str, rgba: dict, size: float = 0.18) -> dict:
    """foxglove.TextPrimitive, billboarded, ``size`` [m] tall."""
    return {"pose": pose(x, y, z), "billboard": True, "font_size": float(size),
            "scale_invariant": False, "color": rgba, "text": words}


def entity(stamp_ns: int, frame: str, ident: str, *, locked: bool = False, **prims) -> dict:
    """foxglove.SceneEntity with every primitive list present (empty unless given)."""
    out = {"timestamp": stamp(stamp_ns), "frame_id": frame, "id": ident,
           "lifetime": {"sec": 0, "nsec": 0}, "frame_locked": locked, "metadata": []}
    for kind in ("arrows", "cubes", "spheres", "cylinders", "lines", "triangles", "texts",
                 "models"):
        out[kind] = list(prims.pop(kind, ()))
    if prims:
        raise TypeError(f"unknown primitive lists {sorted(prims)}")
    return out


def scene_update(entities: Sequence[dict], delete_ids: Sequence[str] = (), stamp_ns: int = 0
                 ) -> dict:
    """foxglove.SceneUpdate: delete entities by id (type MATCHING_ID), then add ``entities``."""
    return {"deletions": [{"timestamp": stamp(stamp_ns), "type": 0, "id": i} for i in delete_ids],
            "entities": list(entities)}


# -- messages --------------------------------------------------------------------------------
def laser_scan(scan: Scan) -> dict:
    """Scan -> foxglove.LaserScan in frame ``laser``.

    JSON has no infinity: a beam with no return (``inf``) or an invalid one (``nan``) is sent
    as :data:`NO_RETURN_M` (0 m, a point at the sensor, hidden inside the robot's footprint).
    """
    ranges = np.asarray(scan.ranges, dtype=float)
    n = ranges.size
    ranges = np.where(np.isfinite(ranges), ranges, NO_RETURN_M)
    end = scan.angle_min + scan.angle_increment * max(n - 1, 0)
    return {"timestamp": stamp(scan.stamp_ns), "frame_id": LASER, "pose": pose(),
            "start_angle": float(scan.angle_min), "end_angle": float(end),
            "ranges": ranges.tolist(), "intensities": []}


def transform(stamp_ns: int, parent: str, child: str, x: float, y: float, z: float,
              yaw: float) -> dict:
    """foxglove.FrameTransform."""
    return {"timestamp": stamp(stamp_ns), "parent_frame_id": parent, "child_frame_id": child,
            "translation": vec3(x, y, z), "rotation": yaw_quat(yaw)}


def robot_transforms(odom: Odometry) -> dict:
    """Pose -> foxglove.FrameTransforms ``world`` -> ``base_link``."""
    return {"transforms": [transform(odom.stamp_ns, WORLD, BASE, odom.x, odom.y, 0.0, odom.yaw)]}


def laser_transforms(scan: Scan) -> dict:
    """Scan's sensor pose -> foxglove.FrameTransforms ``base_link`` -> ``laser``."""
    return {"transforms": [transform(scan.stamp_ns, BASE, LASER, scan.sensor_x, scan.sensor_y,
                                     LIDAR_HEIGHT_M, scan.sensor_yaw)]}


def pose_in_frame(stamp_ns: int, x: float, y: float, yaw: float = 0.0,
                  frame: str = WORLD) -> dict:
    """foxglove.PoseInFrame."""
    return {"timestamp": stamp(stamp_ns), "frame_id": frame, "pose": pose(x, y, 0.0, yaw)}


def robot_pose(odom: Odometry) -> dict:
    """The robot's pose from odometry as a foxglove.PoseInFrame (x, y [m], yaw [rad])."""
    return pose_in_frame(odom.stamp_ns, odom.x, odom.y, odom.yaw)


def goal_pose(goal: Goal) -> dict:
    """The goal as a foxglove.PoseInFrame (x, y [m], no heading)."""
    return pose_in_frame(goal.stamp_ns, goal.x, goal.y)


def log(stamp_ns: int, level: int, name: str, message: str) -> dict:
    """foxglove.Log (no source file: ``file`` empty, ``line`` 0)."""
    return {"timestamp": stamp(stamp_ns), "level": level, "message": message, "name": name,
            "file": "", "line": 0}


def event_log(ev: Event) -> dict:
    """Event -> foxglove.Log: warnings for collisions, stagnation, watchdog stops and
    timeouts, errors for node faults, info for the rest."""
    where = f" at ({ev.x:.2f}, {ev.y:.2f})" if math.isfinite(ev.x) and math.isfinite(ev.y) else ""
    detail = f": {ev.detail}" if ev.detail else ""
    return log(ev.stamp_ns, EVENT_LEVELS.get(ev.kind, LOG_INFO), ev.source,
               f"{ev.kind}{where}{detail}")


def plot_dict(msg: BatteryState | Twist | PlannerStatus | Odometry) -> dict:
    """A message as a JSON object for the Plot panel: its fields, ``timestamp`` as {sec, nsec}
    and ``t`` [s]; non-finite floats become null (JSON has none)."""
    out: dict = {"timestamp": stamp(msg.stamp_ns), "t": msg.stamp_ns / 1e9}
    for k, v in msg.to_dict().items():
        out[k] = None if isinstance(v, float) and not math.isfinite(v) else v
    return out


def plot_schema(msg_type) -> dict:
    """JSON Schema of :func:`plot_dict` for ``msg_type`` (from the message's own schema)."""
    src = msg_type.json_schema()
    props = {k: v for k, v in src["properties"].items() if k != "_type"}
    for name, prop in props.items():
        if prop.get("type") == "number":
            props[name] = {**prop, "type": ["number", "null"]}
    time_s = {"type": "object", "properties": {"sec": {"type": "integer", "minimum": 0},
                                               "nsec": {"type": "integer", "minimum": 0,
                                                        "maximum": 999_999_999}},
              "required": ["sec", "nsec"]}
    props = {"timestamp": time_s, "t": {"type": "number", "description": "stamp_ns [s]"},
             **props}
    return {"$schema": "https://json-schema.org/draft/2020-12/schema",
            "title": f"papf.{msg_type.__name__}", "description": src["description"],
            "type": "object", "properties": props,
            "required": ["timestamp", "t"] + [r for r in src["required"] if r != "_type"]}
