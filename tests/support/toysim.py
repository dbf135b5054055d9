"""The planner in the one offline closed loop on a toy world (:mod:`worlds.toy`): the
robot a point, commands applied as they come, no start jitter, ground-truth odometry, and
a collision does not end the run (``min_clearance`` tells). For tests only."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from common import robot
from papf.offline.unicycle import closed_loop
from worlds import World
from worlds.geometry import clearance
from worlds.toy import box_segments, cast_scan, toy_world  # noqa: F401 - the tests' toolbox

SCAN_PERIOD_S = 1.0 / robot.LIDAR_RATE_HZ   # [s] 10 Hz


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
