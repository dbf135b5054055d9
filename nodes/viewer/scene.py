"""The 3-D scene as foxglove.SceneUpdate dicts (pure): the world, the robot, the planner's mind.

:func:`world_scene` (static obstacles, road, start and goal), :func:`moving_scene`,
:func:`footprint_scene`, :func:`objects_scene` (tracks), :func:`bodies_scene` (a fleet's
other robots and the people) and :func:`mind_scene` (one planner cycle, as the PAPF paper
drew it in RViz). Colours are the matplotlib pictures' (``MIND_COLOURS``). Used by the
viewer's core and ``papf export foxglove``.
"""

from __future__ import annotations

import math

import numpy as np

from common.robot import BODY_HEIGHT_M, BODY_LENGTH_M, BODY_WIDTH_M
from nodes.viewer.convert import (
    BASE,
    LINE_LIST,
    WORLD,
    arrow,
    colour,
    cube,
    cylinder,
    entity,
    line,
    scene_update,
    sphere,
    text,
)
from schemas.messages import Bodies, Objects, PlannerState
from worlds import World

# (r, g, b, a) 0..1; the matplotlib pictures use the same. A planner's own debug output
# carries its own colours (PlannerState.debug: the plug-in's declared style).
MIND_COLOURS = {
    "obstacle": (0.35, 0.35, 0.35, 1.0),
    "start": (0.17, 0.63, 0.17, 1.0),
    "goal": (0.84, 0.15, 0.16, 1.0),
    "robot": (0.12, 0.47, 0.71, 0.6),
    "prediction": (0.42, 0.15, 0.75, 1.0),
    "temporary_goal": (0.09, 0.75, 0.81, 1.0),
    "force": (0.15, 0.15, 0.15, 1.0),
    "moving": (0.8, 0.4, 0.0, 1.0),
    "track": (0.0, 0.6, 0.6, 0.7),
    "road": (0.95, 0.85, 0.2, 1.0),
    "other_robot": (0.45, 0.45, 0.45, 0.7),
    "person": (0.58, 0.4, 0.74, 0.7),
}
ROAD_MARGIN_M = 5.0      # [m] road lines drawn this far beyond the world's extent along x
DASH_M = 0.5             # [m] dash and gap of a broken road line
TEMP_GOAL_DIAMETER_M = 0.16
FORCE_MIN_M, FORCE_MAX_M = 0.15, 0.8   # [m] drawn length of the force arrow (log-scaled |F|)


def c(name: str) -> dict:
    """The foxglove.Color of the mind layer ``name`` (:data:`MIND_COLOURS`)."""
    return colour(*MIND_COLOURS[name])


def _obstacle_prims(obstacles, rgba: dict) -> dict:
    """Each obstacle's solid (its kind's :meth:`~worlds.kinds.base.Kind.solids`) as primitives."""
    prims = {"cubes": [], "cylinders": [], "spheres": []}
    for s in (s for ob in obstacles for s in ob.model.solids(ob)):
        if s.form == "cube":
            prims["cubes"].append(cube(*s.center, s.yaw, s.size, rgba))
        elif s.form == "sphere":
            prims["spheres"].append(sphere(*s.center, s.size[0], rgba))
        else:
            prims["cylinders"].append(cylinder(*s.center, s.size[0] / 2, s.size[2], rgba))
    return prims


def _x_extent(world: World) -> tuple[float, float]:
    xs = [world.start[0], world.goal[0]] + [ob.center[0] for ob in world.obstacles]
    for ob in world.obstacles:
        if ob.motion is not None:
            xs += [sample[1] for sample in ob.motion.track]
    return min(xs) - ROAD_MARGIN_M, max(xs) + ROAD_MARGIN_M


def road_lines(world: World) -> list[dict]:
    """The road's painted lines: solid edges as strips, broken lines as dashes (LINE_LIST)."""
    if world.road is None:
        return []
    x0, x1 = _x_extent(world)
    out = []
    for rl in world.road.lines():
        if rl.kind == "solid":
            out.append(line([(x0, rl.y), (x1, rl.y)], c("road"), 0.05, z=0.005))
        else:
            xs = np.arange(x0, x1, 2 * DASH_M)
            pts = [p for x in xs for p in ((x, rl.y), (min(x + DASH_M, x1), rl.y))]
            out.append(line(pts, c("road"), 0.04, z=0.005, kind=LINE_LIST))
    return out


def world_scene(world: World, stamp_ns: int = 0) -> dict:
    """The world's static obstacles, road, start and goal (entity ``world``, frame ``world``)."""
    prims = _obstacle_prims([ob for ob in world.obstacles if ob.motion is None], c("obstacle"))
    gx, gy = world.goal[0], world.goal[1]
    gz = world.goal[2] if world.dims == 3 else 0.0
    prims["cylinders"].append(cylinder(gx, gy, gz + 0.005, world.tolerance, 0.01,
                                       {**c("goal"), "a": 0.35}))
    texts = [text(gx, gy, gz + 0.35, "goal", c("goal"))]
    sx, sy = world.start[0], world.start[1]
    arrows = [arrow(sx, sy, 0.01, world.start[2] if world.dims == 2 else 0.0, 0.3, c("start"))]
    return scene_update([entity(stamp_ns, WORLD, "world", texts=texts, arrows=arrows,
                                lines=road_lines(world), **prims)])


def moving_scene(world: World, stamp_ns: int) -> dict:
    """The moving obstacles where they are at ``stamp_ns`` (entity ``moving``)."""
    moving = [ob.at(stamp_ns / 1e9) for ob in world.obstacles if ob.motion is not None]
    return scene_update([entity(stamp_ns, WORLD, "moving", **_obstacle_prims(moving,
                                                                               c("moving")))])


OBJECT_HEIGHT_M = 0.3   # [m] drawn height of a track's box (tracks are 2-D)


def objects_scene(msg: Objects) -> dict:
    """Obstacle tracks (``objects``: ground truth or the tracker) as boxes of their length and
    width, a velocity arrow (1 s of travel) and the track id (entity ``objects``)."""
    cubes, arrows, texts = [], [], []
    for tr in msg.tracks:
        size = (max(tr.length, 0.05), max(tr.width, 0.05), OBJECT_HEIGHT_M)
        cubes.append(cube(tr.x, tr.y, OBJECT_HEIGHT_M / 2, tr.yaw, size, c("track")))
        speed = math.hypot(tr.vx, tr.vy)
        if speed > 1e-3:
            arrows.append(arrow(tr.x, tr.y, OBJECT_HEIGHT_M + 0.05, math.atan2(tr.vy, tr.vx),
                                max(speed, 0.15), {**c("track"), "a": 1.0}))
        texts.append(text(tr.x, tr.y, OBJECT_HEIGHT_M + 0.25, f"{msg.source} {tr.id}",
                          {**c("track"), "a": 1.0}, 0.1))
    return scene_update([entity(msg.stamp_ns, WORLD, "objects", cubes=cubes, arrows=arrows,
                                texts=texts)])


PERSON_HEIGHT_M = 1.7   # [m] drawn height of a person's cylinder


def bodies_scene(msg: Bodies) -> dict:
    """A fleet's other robots (chassis boxes, named) and the people (cylinders) at a scan
    instant (``sim/bodies``; entity ``fleet``)."""
    size = (BODY_LENGTH_M, BODY_WIDTH_M, BODY_HEIGHT_M)
    cubes = [cube(x, y, BODY_HEIGHT_M / 2, yaw, size, c("other_robot"))
             for x, y, yaw in zip(msg.robot_x, msg.robot_y, msg.robot_yaw, strict=True)]
    texts = [text(x, y, BODY_HEIGHT_M + 0.2, name, {**c("other_robot"), "a": 1.0}, 0.1)
             for name, x, y in zip(msg.robots, msg.robot_x, msg.robot_y, strict=True)]
    people = [cylinder(x, y, PERSON_HEIGHT_M / 2, r, PERSON_HEIGHT_M, c("person"))
              for x, y, r in zip(msg.person_x, msg.person_y, msg.person_radius, strict=True)
              if r > 0]   # radius 0: a replayed person not in the scene now
    return scene_update([entity(msg.stamp_ns, WORLD, "fleet", cubes=cubes, texts=texts,
                                cylinders=people)])


def footprint_scene(stamp_ns: int = 0) -> dict:
    """The chassis box and a heading arrow in ``base_link`` (entity ``robot``)."""
    body = cube(0.0, 0.0, BODY_HEIGHT_M / 2, 0.0, (BODY_LENGTH_M, BODY_WIDTH_M, BODY_HEIGHT_M),
                c("robot"))
    heading = arrow(0.0, 0.0, BODY_HEIGHT_M + 0.02, 0.0, 0.25, {**c("robot"), "a": 1.0})
    return scene_update([entity(stamp_ns, BASE, "robot", locked=True, cubes=[body],
                                arrows=[heading])])


def _force_arrow(state: PlannerState, robot_xy: tuple[float, float] | None) -> list[dict]:
    fx, fy = state.force
    mag = math.hypot(fx, fy)
    if robot_xy is None or not (mag > 0 and math.isfinite(mag)):
        return []
    length = min(FORCE_MAX_M, FORCE_MIN_M + 0.15 * math.log1p(mag))
    return [arrow(robot_xy[0], robot_xy[1], 0.3, math.atan2(fy, fx), length, c("force"))]


def mind_scene(state: PlannerState, robot_xy: tuple[float, float] | None = None) -> dict:
    """One planner cycle as entity ``mind`` (replaces the previous cycle's): the generic parts
    every planner has, and the plug-in's own fields drawn by kind in their declared style."""
    lines, spheres, words = _debug_primitives(state.debug)
    if len(state.predicted_path) > 1:
        lines.append(line(state.predicted_path, c("prediction"), 0.035, z=0.03))
    if len(state.temporary_goal) >= 2:
        tg = state.temporary_goal
        spheres.append(sphere(tg[0], tg[1], 0.08, TEMP_GOAL_DIAMETER_M, c("temporary_goal")))
    texts = []
    if robot_xy is not None:
        caption = " · ".join([f"{state.algorithm}: {state.mode}", *words])
        texts.append(text(robot_xy[0], robot_xy[1], 0.55, caption, {**c("force"), "a": 1.0}, 0.12))
    return scene_update([entity(state.stamp_ns, WORLD, "mind", lines=lines, spheres=spheres,
                                arrows=_force_arrow(state, robot_xy), texts=texts)])


def _debug_primitives(debug) -> tuple[list, list, list[str]]:
    """(lines, spheres, caption words) of a plan's debug values, by kind: points and a point
    as spheres of the style's diameter, paths as lines of its thickness (thin ones beneath
    the prediction), scalars and counts as words beside the mode."""
    lines, spheres, words = [], [], []
    for d in debug:
        rgba = colour(*d.colour)
        if d.kind in ("points", "point"):
            spheres += [sphere(p[0], p[1], 0.1, d.size, rgba) for p in d.points]
        elif d.kind == "paths":
            z = 0.02 if d.size < 0.035 else 0.05
            lines += [line(p, rgba, d.size, z=z) for p in d.paths if len(p) > 1]
        elif not math.isnan(d.value):
            words.append(d.words())
    return lines, spheres, words
