"""Offline planning in 3-D (Wang, Sec. 5: sphere obstacles, goal with z) — a point robot.

Wang simulates a point in MATLAB that moves along the resultant force; we do the same with
the registry's strategies on the shared N-D APF core:

- **Obstacle points**: returns of a simulated 3-D range sensor at the robot — :data:`RAYS`
  rays in a Fibonacci-sphere pattern (near-uniform directions), each stopped at the first
  sphere surface it meets within :data:`RANGE_MAX_M`. So only the visible surfaces give
  points, like the 2-D LiDAR, and ``L`` (APF k_VO = 10 / L) is the number of rays: a wall
  filling half the view repels as hard as in 2-D.
- **Motion**: the point moves along F by ``V dt`` with ``V = Limit(|F|, V_max)`` (eq. 5 with
  no heading error: a point has no orientation), every control period ``dt``.
- **Collision**: the point inside a sphere (no body radius: a point robot, as Wang's).
- **Stagnation**: the strategy's own verdict, or the planner core's watch
  (:class:`nodes.planner.stagnation.StagnationWatch`, the same rule as in 2-D).

World convention: in a 3-D world (3-number goal) ``[robot] start`` is (x, y, z) [m], not
(x, y, yaw). Planners that need the planar scan geometry (AR-APF) are 2-D only.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from common.errors import ConfigError
from common.robot import MOVING_SPEED
from common.units import NS_PER_S
from nodes.planner.core import ScanView
from nodes.planner.field import APFParams
from nodes.planner.registry import declared
from nodes.planner.stagnation import StagnationWatch
from papf.offline.result import PlanResult
from worlds import World
from worlds.shapes import sphere_clearance, spheres_of

RAYS = 4000               # [-] rays of the 3-D range sensor (~3.2 deg apart; ours)
RANGE_MAX_M = 25.0        # [m] as the RPLIDAR A3
PLANAR_ONLY = tuple(declared("planar_only"))  # strategies that read the planar scan (beam angles), not just points


def fibonacci_directions(n: int) -> np.ndarray:
    """(n, 3) unit vectors spread near-uniformly over the sphere (golden-angle spiral)."""
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * i / n
    r = np.sqrt(1.0 - z * z)
    phi = math.pi * (3.0 - math.sqrt(5.0)) * i
    return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])


def cast_points(pos: np.ndarray, spheres: np.ndarray, dirs: np.ndarray,
                range_max: float = RANGE_MAX_M) -> np.ndarray:
    """First hit of each ray from ``pos`` on any sphere, as (K, 3) points [m] (ray order)."""
    best = np.full(dirs.shape[0], np.inf)
    for cx, cy, cz, rad in spheres:
        o = pos - np.array([cx, cy, cz])
        b = dirs @ o
        disc = b * b - (o @ o - rad * rad)
        with np.errstate(invalid="ignore"):
            t = -b - np.sqrt(disc)
        best = np.where((disc >= 0) & (t > 0) & (t < best), t, best)
    hit = best <= range_max
    return pos + dirs[hit] * best[hit, None]


def plan_3d(world: World, planner, name: str, seed: int, max_time_s: float, dt: float,
            keep_states: bool):
    """Closed loop of a point robot (see module doc)."""
    if name in PLANAR_ONLY:
        raise ConfigError(f"planner {name!r} reads the planar LiDAR scan and is 2-D only; "
                          "3-D worlds take apf, papf or wang")
    spheres = spheres_of(world)
    dirs = fibonacci_directions(RAYS)
    apf: APFParams = planner.apf
    if apf.scale_to_scan:
        apf = dataclasses.replace(apf, lidar_points=RAYS)
    strategy = planner.strategy
    strategy.reset()
    watch = StagnationWatch()
    pos = np.array(world.start[:3], dtype=float)
    goal = np.array(world.goal[:3], dtype=float)
    rows, states = [(0.0, *pos)], []
    min_clear = sphere_clearance(pos, spheres)
    outcome, reason, steps, moved_t, cycles = "", "", 0, None, 0
    while not outcome:
        t = steps * dt
        dist = float(np.linalg.norm(goal - pos))
        if dist <= world.tolerance:
            outcome, reason = "reached", f"within {world.tolerance} m of the goal"
            break
        points = cast_points(pos, spheres, dirs)
        view = ScanView(origin=pos.copy(), angles=np.zeros(0), ranges=np.zeros(0),
                        points=points, valid=np.zeros(0, dtype=bool))
        out = strategy.plan(pos, 0.0, goal, view, apf)
        cycles += 1
        if keep_states:
            states.append(out)
        why = out.stagnated or watch.check(round(t * NS_PER_S), dist, apf, pos, out.searching)
        if why:
            outcome, reason = "stagnated", why
            break
        force = np.asarray(out.force, dtype=float)
        norm = float(np.linalg.norm(force))
        speed = min(norm, apf.v_max)              # eq. 5 with no heading error
        if norm > 0:
            pos = pos + force / norm * speed * dt
        if moved_t is None and speed > MOVING_SPEED:
            moved_t = t
        steps += 1
        rows.append((steps * dt, *pos))
        c = sphere_clearance(pos, spheres)
        min_clear = min(min_clear, c)
        if c < 0:
            outcome, reason = "collision", f"point inside a sphere at {np.round(pos, 2)}"
        elif steps * dt >= max_time_s:
            outcome, reason = "timeout", f"no outcome within {max_time_s:g} s"
    t_end = steps * dt
    arr = np.array(rows)
    start_t = moved_t if moved_t is not None else t_end
    return PlanResult(world=world.name, planner=name, seed=seed, outcome=outcome, reason=reason,
                      path=arr[:, 1:4], times=arr[:, 0], headings=np.zeros(0),
                      duration_s=max(0.0, t_end - start_t), sim_time_s=t_end,
                      min_clearance_m=min(min_clear, 1.0), collisions=int(outcome == "collision"),
                      motion="point3d", cycles=cycles, states=states)
