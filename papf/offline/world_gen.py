"""Seeded random worlds for the planner benchmark, with a solvability check.

``generate(seed, index)`` draws one world from ``numpy.random.default_rng([seed, index])``:
the same (seed, index) always gives the same world. Every world is a walled arena (the
robot cannot drive round everything) with start (0, 0) facing +x and a goal 4-7 m ahead,
and one of three layouts (:data:`KINDS`, in turn by index):

- ``field``: 4-10 boxes and cylinders scattered within 1 m of the start-goal line;
- ``dead_end``: a U-shaped dead end (inner width 0.6-1.6 m, depth 0.4-1.5 m) opening
  towards the robot near the start-goal line, plus 0-3 scattered obstacles;
- ``gap``: a barrier across the whole arena with one narrow gap of 0.45-0.7 m (the robot
  is 0.235 m wide), plus 0-3 scattered obstacles.

Solvable (:func:`is_solvable`) = a 4-connected path of free cells joins start and goal on an
occupancy grid (:data:`GRID_M`) whose obstacles are inflated by the robot's circumscribed
radius (:data:`ROBOT_RADIUS_M`): a robot of that disc fits through in any heading.
:func:`bottleneck_width` is the widest disc that still gets through, doubled: the narrowest
passage of the best route.
"""

from __future__ import annotations

import json
import math
from collections import deque

import numpy as np

from common.errors import ConfigError
from worlds import World, parse_world
from worlds.geometry import signed_distance

KINDS = ("field", "dead_end", "gap")
ROBOT_RADIUS_M = math.hypot(0.200, 0.235) / 2   # [m] 0.154: the chassis box's circumscribed disc
GRID_M = 0.05              # [m] occupancy-grid cell
WALL_T = 0.1               # [m] thickness of arena, barrier and dead-end walls
START_CLEAR_M = 0.6        # [m] no obstacle surface closer than this to the start
GOAL_CLEAR_M = 0.5         # [m] ... or to the goal
GAP_RANGE_M = (0.45, 0.7)  # [m] narrow-gap widths (issue 3)
U_WIDTH_M = (0.6, 1.6)     # [m] dead-end inner widths
U_DEPTH_M = (0.4, 1.5)     # [m] dead-end depths


# -- solvability ---------------------------------------------------------------------
def occupancy(world: World, grid_m: float = GRID_M, inflate_m: float = ROBOT_RADIUS_M,
              margin_m: float = 0.5):
    """(blocked bool grid [iy, ix], origin (x0, y0) [m]) over the world's extent + margin."""
    xs = [world.start[0], world.goal[0]]
    ys = [world.start[1], world.goal[1]]
    for ob in world.obstacles:
        reach = ob.model.reach(ob)
        xs += [ob.center[0] - reach, ob.center[0] + reach]
        ys += [ob.center[1] - reach, ob.center[1] + reach]
    x0, y0 = min(xs) - margin_m, min(ys) - margin_m
    nx = int(math.ceil((max(xs) + margin_m - x0) / grid_m)) + 1
    ny = int(math.ceil((max(ys) + margin_m - y0) / grid_m)) + 1
    gx, gy = np.meshgrid(x0 + grid_m * np.arange(nx), y0 + grid_m * np.arange(ny))
    d = signed_distance(world, np.column_stack([gx.ravel(), gy.ravel()]))
    return (d <= inflate_m).reshape(ny, nx), (x0, y0)


def is_solvable(world: World, grid_m: float = GRID_M, inflate_m: float = ROBOT_RADIUS_M) -> bool:
    """True if a robot disc of ``inflate_m`` can get from start to goal (BFS on the grid)."""
    if world.dims != 2:
        raise ConfigError(f"is_solvable: world {world.name!r} is {world.dims}-D; only 2-D worlds")
    blocked, (x0, y0) = occupancy(world, grid_m, inflate_m)
    ny, nx = blocked.shape

    def cell(x, y):
        return int(round((y - y0) / grid_m)), int(round((x - x0) / grid_m))

    start, goal = cell(*world.start[:2]), cell(*world.goal[:2])
    if blocked[start] or blocked[goal]:
        return False
    seen = np.zeros_like(blocked)
    seen[start] = True
    todo = deque([start])
    while todo:
        iy, ix = todo.popleft()
        if (iy, ix) == goal:
            return True
        for jy, jx in ((iy + 1, ix), (iy - 1, ix), (iy, ix + 1), (iy, ix - 1)):
            if 0 <= jy < ny and 0 <= jx < nx and not blocked[jy, jx] and not seen[jy, jx]:
                seen[jy, jx] = True
                todo.append((jy, jx))
    return False


def bottleneck_width(world: World, hi_m: float = 2.0, tol_m: float = 0.02,
                     grid_m: float = GRID_M) -> float:
    """Width of the narrowest passage on the best start-goal route [m] (bisection on the
    inflation radius of :func:`is_solvable`; ``2 * hi_m`` if wider than that, 0 if none)."""
    lo, hi = 0.0, hi_m
    if not is_solvable(world, grid_m, lo):
        return 0.0
    if is_solvable(world, grid_m, hi):
        return 2.0 * hi
    while hi - lo > tol_m / 2:
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if is_solvable(world, grid_m, mid) else (lo, mid)
    return 2.0 * lo


# -- generation ---------------------------------------------------------------------
def _wall(a, b) -> dict:
    return {"kind": "wall", "from": [float(a[0]), float(a[1])], "to": [float(b[0]), float(b[1])],
            "thickness": WALL_T}


def _arena(x0, y0, x1, y1) -> list[dict]:
    pts = [(x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0)]
    return [_wall(pts[i], pts[i + 1]) for i in range(4)]


def _scatter(rng, n, goal, half_w, keep_out) -> list[dict]:
    """``n`` boxes/cylinders between start and goal, clear of start, goal and ``keep_out``."""
    out, tries = [], 0
    while len(out) < n and tries < 200 * max(n, 1):
        tries += 1
        x = rng.uniform(0.6, goal[0] - 0.4)
        y = float(np.clip(goal[1] * x / goal[0] + rng.uniform(-1.0, 1.0), -half_w + 0.4, half_w - 0.4))
        if rng.random() < 0.5:
            ob = {"kind": "cylinder", "center": [x, y], "radius": float(rng.uniform(0.1, 0.3))}
            reach = ob["radius"]
        else:
            size = rng.uniform(0.2, 0.6, 2)
            ob = {"kind": "box", "center": [x, y], "size": [float(size[0]), float(size[1])],
                  "yaw": float(rng.uniform(-math.pi, math.pi))}
            reach = float(np.hypot(*size) / 2)
        if (math.hypot(x, y) - reach < START_CLEAR_M
                or math.hypot(x - goal[0], y - goal[1]) - reach < GOAL_CLEAR_M
                or any(math.hypot(x - kx, y - ky) < kr + reach for kx, ky, kr in keep_out)):
            continue
        out.append(ob)
    return out


def _dead_end(rng, goal) -> tuple[list[dict], tuple]:
    """A U opening towards the start near the start-goal line; returns walls and a keep-out disc."""
    w, d = rng.uniform(*U_WIDTH_M), rng.uniform(*U_DEPTH_M)
    line = np.array(goal) / np.linalg.norm(goal)
    s0 = rng.uniform(1.0, max(1.1, np.linalg.norm(goal) - d - 1.0))
    rot = math.atan2(line[1], line[0]) + rng.uniform(-math.radians(20), math.radians(20))
    u = np.array([math.cos(rot), math.sin(rot)])
    n = np.array([-u[1], u[0]])
    base = line * s0 + np.array([-line[1], line[0]]) * rng.uniform(-0.4, 0.4)
    e = w / 2 + WALL_T / 2
    walls = [_wall(base + u * d - n * e, base + u * d + n * e),
             _wall(base - n * w / 2, base + u * d - n * w / 2),
             _wall(base + n * w / 2, base + u * d + n * w / 2)]
    c = base + u * d / 2
    return walls, (c[0], c[1], math.hypot(w / 2, d / 2) + 0.3)


def _gap(rng, goal, half_w) -> tuple[list[dict], tuple]:
    """A barrier across the arena (tilted up to 15 deg) with one gap of GAP_RANGE_M."""
    g = rng.uniform(*GAP_RANGE_M)
    xb = rng.uniform(1.5, goal[0] - 1.5)
    tilt = rng.uniform(-math.radians(15), math.radians(15))
    t = np.array([-math.sin(tilt), math.cos(tilt)])
    s_edge = half_w / math.cos(tilt) + WALL_T
    sg = rng.uniform(-1.0, 1.0)
    base = np.array([xb, 0.0])
    walls = [_wall(base - t * s_edge, base + t * (sg - g / 2)),
             _wall(base + t * (sg + g / 2), base + t * s_edge)]
    return walls, (xb, 0.0, 0.6)


def generate(seed: int, index: int = 0, kind: str | None = None) -> World:
    """World ``index`` of the random set ``seed`` (kind: ``KINDS[index % 3]`` unless given)."""
    kind = kind or KINDS[index % len(KINDS)]
    if kind not in KINDS:
        raise ConfigError(f"random world kind {kind!r} is not one of {', '.join(KINDS)}")
    rng = np.random.default_rng([seed, index])
    length = rng.uniform(4.0, 7.0)
    goal = (float(length), float(rng.uniform(-1.0, 1.0)))
    half_w = float(rng.uniform(1.5, 2.25))
    obstacles = _arena(-1.0, -half_w, length + 1.0, half_w)
    if kind == "field":
        obstacles += _scatter(rng, int(rng.integers(4, 11)), goal, half_w, [])
    else:
        walls, keep = _dead_end(rng, goal) if kind == "dead_end" else _gap(rng, goal, half_w)
        obstacles += walls + _scatter(rng, int(rng.integers(0, 4)), goal, half_w, [keep])
    data = {"name": f"rand-{seed}-{index:03d}-{kind}",
            "description": f"random {kind} world {index} of set {seed} (papf.offline.world_gen)",
            "robot": {"start": [0.0, 0.0, 0.0]},
            "goal": {"position": list(goal), "tolerance": 0.1}, "obstacles": obstacles}
    return parse_world(data, source=f"<random {seed}/{index}>")


def generate_solvable(n: int, seed: int = 0, kinds=KINDS) -> tuple[list[World], int]:
    """The first ``n`` solvable worlds of set ``seed`` (kinds in turn); and how many were rejected."""
    worlds, rejected, index = [], 0, 0
    while len(worlds) < n:
        w = generate(seed, index, kinds[index % len(kinds)])
        index += 1
        if is_solvable(w):
            worlds.append(w)
        else:
            rejected += 1
        if index > 20 * n + 100:
            raise ConfigError(f"only {len(worlds)} of {n} random worlds were solvable")
    return worlds, rejected


def world_to_toml(world: World) -> str:
    """The world in the TOML format of docs/worlds.md (walls written as yawed boxes)."""
    def v(x):
        return "[" + ", ".join(repr(float(a)) for a in x) + "]"

    lines = [f"name = {json.dumps(world.name)}", f"description = {json.dumps(world.description)}",
             "[robot]", f"start = {v(world.start)}", "[goal]", f"position = {v(world.goal)}",
             f"tolerance = {float(world.tolerance)!r}"]
    for ob in world.obstacles:
        lines.append("[[obstacles]]")
        for key, value in ob.model.table(ob).items():
            text = v(value) if isinstance(value, list) else (
                json.dumps(value) if isinstance(value, str) else repr(float(value)))
            lines.append(f"{key} = {text}")
    return "\n".join(lines) + "\n"
