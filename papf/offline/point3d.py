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
- **Stagnation**: the strategy's own verdict, or the planner's watch (no progress of
  ``stagnation_progress_m`` within ``stagnation_window_s``), as in 2-D.

World convention: in a 3-D world (3-number goal) ``[robot] start`` is (x, y, z) [m], not
(x, y, yaw). Planners that need the planar scan geometry (AR-APF) are 2-D only.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from common.errors import ConfigError
from nodes.planner.apf import APFParams
from nodes.planner.core import ScanView
from papf.offline.result import PlanResult
from worlds import World

RAYS = 4000               # [-] rays of the 3-D range sensor (~3.2 deg apart; ours)
RANGE_MAX_M = 25.0        # [m] as the RPLIDAR A3
PLANAR_ONLY = ("arapf",)  # strategies that read the planar scan (beam angles), not just points


def fibonacci_directions(n: int) -> np.ndarray:
    """(n, 3) unit vectors spread near-uniformly over the sphere (golden-angle spiral)."""
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * i / n
    r = np.sqrt(1.0 - z * z)
    phi = math.pi * (3.0 - math.sqrt(5.0)) * i
    return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])


def spheres_of(world: World) -> np.ndarray:
    """(K, 4) rows (cx, cy, cz, radius) of the world's sphere obstacles; ConfigError otherwise."""
    rows = []
    for i, ob in enumerate(world.obstacles):
        if 3 not in ob.model.world_dims:
            raise ConfigError(f"world {world.name!r}: obstacles[{i}] is a {ob.kind}; 3-D worlds "
                              "take only kind = \"sphere\" obstacles")
        rows.append((*ob.center[:3], ob.radius))
    return np.array(rows, dtype=float).reshape(-1, 4)


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


def clearance(pos: np.ndarray, spheres: np.ndarray) -> float:
    """Distance from the point to the nearest sphere surface [m] (< 0 inside); inf if none."""
    if spheres.shape[0] == 0:
        return math.inf
    return float(np.min(np.linalg.norm(spheres[:, :3] - pos, axis=1) - spheres[:, 3]))


class ProgressWatch:
    """No progress of ``progress_m`` towards the goal within ``window_s`` -> a reason string.

    The same rule as the planner core's stagnation watch (APFParams.stagnation_*).
    """

    def __init__(self, window_s: float, progress_m: float):
        self.window_s, self.progress_m = window_s, progress_m
        self.best, self.best_t = math.inf, 0.0

    def check(self, t: float, dist: float) -> str:
        if dist < self.best - self.progress_m or not math.isfinite(self.best):
            self.best, self.best_t = dist, t
            return ""
        if t - self.best_t > self.window_s:
            return (f"no progress > {self.progress_m} m towards the goal in {self.window_s} s "
                    f"(best {self.best:.3f} m)")
        return ""


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
    watch = ProgressWatch(apf.stagnation_window_s, apf.stagnation_progress_m)
    pos = np.array(world.start[:3], dtype=float)
    goal = np.array(world.goal[:3], dtype=float)
    rows, states = [(0.0, *pos)], []
    min_clear = clearance(pos, spheres)
    outcome, reason, steps, moved_t = "", "", 0, None
    while not outcome:
        t = steps * dt
        dist = float(np.linalg.norm(goal - pos))
        if dist <= world.tolerance:
            outcome, reason = "reached", f"within {world.tolerance} m of the goal"
            break
        reason = watch.check(t, dist)
        if reason:
            outcome = "stagnated"
            break
        points = cast_points(pos, spheres, dirs)
        view = ScanView(origin=pos.copy(), angles=np.zeros(0), ranges=np.zeros(0),
                        points=points, valid=np.zeros(0, dtype=bool))
        out = strategy.plan(pos, 0.0, goal, view, apf)
        if keep_states:
            states.append(out)
        if out.stagnated:
            outcome, reason = "stagnated", out.stagnated
            break
        force = np.asarray(out.force, dtype=float)
        norm = float(np.linalg.norm(force))
        speed = min(norm, apf.v_max)              # eq. 5 with no heading error
        if norm > 0:
            pos = pos + force / norm * speed * dt
        if moved_t is None and speed > 0.01:
            moved_t = t
        steps += 1
        rows.append((steps * dt, *pos))
        c = clearance(pos, spheres)
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
                      states=states)
