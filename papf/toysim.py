"""A light kinematic 2-D world for planner tests and benchmarks: no pybullet, no zenoh.

- :func:`toy_world`: circles ``(x, y, radius)`` and zero-thickness segments
  ``(x0, y0, x1, y1)`` [m] as a :class:`worlds.World` (cylinders and walls);
- :func:`cast_scan`: a noiseless 360-degree scan with exact ray intersection
  (:func:`worlds.geometry.cast_rays`), as a :class:`~schemas.messages.Scan`;
- :func:`simulate`: the planner in the one offline closed loop
  (:func:`papf.sim2d.closed_loop`) with those scans, the robot a point (clearance from
  :func:`worlds.geometry.clearance`), commands applied as they come (no command gate),
  no start jitter, and a collision does not end the run (``min_clearance`` tells).
  Odometry is ground truth: a reproducible stand-in for the stack.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from common import robot
from papf.sim2d import closed_loop
from schemas.messages import Scan
from worlds import Obstacle, World
from worlds.geometry import cast_rays, clearance, segment_wall

SCAN_PERIOD_S = 1.0 / robot.LIDAR_RATE_HZ   # [s] 10 Hz


def toy_world(circles=(), segments=(), start=(0.0, 0.0, 0.0), goal=(5.0, 0.0),
              tolerance: float = 0.1) -> World:
    """A world of ``circles`` (x, y, r) and ``segments`` (x0, y0, x1, y1) [m]."""
    obstacles = tuple(Obstacle("cylinder", "cylinder", (cx, cy), radius=r) for cx, cy, r in circles)
    obstacles += tuple(segment_wall(*seg) for seg in segments)
    return World("toy", "", tuple(start), tuple(goal), tolerance, obstacles)


def box_segments(cx: float, cy: float, sx: float, sy: float) -> tuple:
    """The 4 sides of an axis-aligned box as segments."""
    x0, x1, y0, y1 = cx - sx / 2, cx + sx / 2, cy - sy / 2, cy + sy / 2
    return ((x0, y0, x1, y0), (x1, y0, x1, y1), (x1, y1, x0, y1), (x0, y1, x0, y0))


def cast_scan(world: World, x: float, y: float, yaw: float, stamp_ns: int = 0,
              beams: int = 300, range_max: float = robot.LIDAR_RANGE_MAX_M) -> Scan:
    """Ranges of ``beams`` rays over 360 degrees from (x, y, yaw); inf = no return."""
    inc = 2.0 * math.pi / beams
    ranges = cast_rays(world, x, y, yaw + (-math.pi + inc * np.arange(beams)), range_max)
    return Scan(stamp_ns=stamp_ns, angle_min=-math.pi, angle_increment=inc,
                range_min=robot.LIDAR_RANGE_MIN_M, range_max=range_max,
                ranges=ranges.astype(np.float32))


@dataclass
class SimResult:
    path: np.ndarray                   # (N, 3) x, y, yaw per scan [m, m, rad]
    status: str                        # outcome: reached | stagnated | failed | timeout
    time_s: float                      # sim time at the end [s]
    min_clearance: float               # closest approach to an obstacle surface [m]
    states: list = field(default_factory=list)  # PlannerState per cycle if kept

    @property
    def length(self) -> float:
        return float(np.sum(np.hypot(*np.diff(self.path[:, :2], axis=0).T)))


def simulate(planner, world: World, start=(0.0, 0.0, 0.0), goal=(5.0, 0.0),
             tolerance: float = 0.1, max_time_s: float = 120.0, keep_states: bool = False,
             beams: int = 300) -> SimResult:
    """Closed loop: scan -> planner.step -> unicycle for one scan period, until an outcome."""
    world = World(world.name, world.description, tuple(start), tuple(goal), tolerance,
                  world.obstacles)
    r = closed_loop(world, planner, "toy", 0, tuple(map(float, start)),
                    lambda x, y, yaw, t: cast_scan(world, x, y, yaw, t, beams),
                    lambda x, y, yaw, t: clearance(world, x, y), max_time_s, SCAN_PERIOD_S,
                    keep_states=keep_states, stop_on_collision=False)
    return SimResult(np.column_stack([r.path, r.headings]), r.outcome, r.sim_time_s,
                     r.min_clearance_m, r.states)
