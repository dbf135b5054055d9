"""ORCA as a planner strategy (``--planner orca``): one RVO2 step per control cycle.

Each cycle builds an RVO2 simulator (``pyrvo``; van den Berg, Guy, Lin, Manocha 2011,
"Reciprocal n-body collision avoidance", ISRR) holding the robot as agent 0 - its
circumscribed disc plus ``safety_m``, at its odometry velocity, its preferred velocity
``v_max`` toward the goal (slower within ``v_max`` x 1 s of it) - the tracked people and
robots as agents at their velocities, groups as one disc each, and the scan's static
surroundings as RVO2 line obstacles (:mod:`nodes.planner.neighbours`). RVO2's new velocity
of agent 0 is the holonomic velocity the robot should take; the planner core tracks it on
the ROSbot's unicycle: heading reference = its direction, speed = its size x cos(heading
error) (none beyond 90 deg), turn rate from the shared heading controller (k_theta, w_max)
- the tracking NH-ORCA bounds (Alonso-Mora et al. 2010, "Optimal reciprocal collision
avoidance for multiple non-holonomic robots"), here without its tracking-error term.

Defaults are CrowdNav's ORCA robot (Chen et al. 2019, crowd_nav/policy/orca.py): neighbours
within 10 m, at most 10, time horizons 5 s, radius + 0.01 m... here + 0.05 m, because the
other agents (replayed people, a social-force crowd) may not take their half of the
avoiding that ORCA assumes. Without tracks (``--objects none``) it sees people only as scan
points, static.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nodes.planner.core import Plan, ScanView, Strategy
from nodes.planner.field import APFParams
from nodes.planner.neighbours import (
    agents,
    robot_radius,
    scan_segments,
    to_unicycle,
    with_groups,
)
from nodes.planner.orca.settings import ORCA

OTHER_MAX_SPEED_M_S = 100.0   # [m/s] another agent's cap in RVO2 (its velocity is given)
STEP_S = 0.1                  # [s] the RVO2 time step (the control period)


@dataclass(frozen=True)
class ORCAParams:
    """ORCA's settings (module doc for the defaults)."""

    time_horizon_s: float = 5.0         # [s] against other agents
    time_horizon_obst_s: float = 5.0    # [s] against static obstacles
    neighbor_dist_m: float = 10.0       # [m] agents considered
    max_neighbors: int = 10             # [-]
    safety_m: float = 0.05              # [m] added to the robot's circumscribed radius
    obstacle_range_m: float = 3.0       # [m] scan points turned into obstacles
    group_gap_m: float = 0.6            # [m] people closer than this (discs), moving alike: a group


class ORCAStrategy(Strategy):
    """ORCA (module doc)."""

    name = "orca"
    rank = 6
    roles = ("crowd",)
    colour, colour_map = "tab:olive", "YlGn"
    uses_objects = True           # people and robots as agents with velocities
    Params = ORCAParams
    SPECS = ORCA
    PAPER_PRESET = {"safety_m": 0.02}   # closest to CrowdNav's +0.01 m within our floor

    def __init__(self, params=None):
        super().__init__(params)
        self._tracks: tuple = ()
        self._v = 0.0
        self.last_velocity = np.zeros(2)   # [m/s] RVO2's answer of the last cycle

    def observe(self, objects: tuple, road, t: float, v: float) -> None:
        self._tracks, self._v = tuple(objects), v

    def plan(self, pos: np.ndarray, yaw: float, goal: np.ndarray, view: ScanView,
             apf: APFParams) -> Plan:
        """One RVO2 step (module doc): the heading and speed to track."""
        import pyrvo

        prm = self.params
        rows = with_groups(agents(self._tracks, pos, prm.neighbor_dist_m), prm.group_gap_m)
        sim = pyrvo.RVOSimulator()
        sim.set_time_step(STEP_S)
        own = (self._v * math.cos(yaw), self._v * math.sin(yaw))
        sim.add_agent(tuple(map(float, pos)), prm.neighbor_dist_m, prm.max_neighbors,
                      prm.time_horizon_s, prm.time_horizon_obst_s, robot_radius(prm.safety_m),
                      apf.v_max, own)
        sim.set_agent_pref_velocity(0, _preferred(pos, goal, apf.v_max))
        for x, y, vx, vy, r in rows:
            k = sim.add_agent((float(x), float(y)), prm.neighbor_dist_m, prm.max_neighbors,
                              prm.time_horizon_s, prm.time_horizon_obst_s, float(r),
                              OTHER_MAX_SPEED_M_S, (float(vx), float(vy)))
            sim.set_agent_pref_velocity(k, (float(vx), float(vy)))
        for line in scan_segments(view, pos, rows, prm.obstacle_range_m):
            for a, b in zip(line[:-1], line[1:], strict=True):
                sim.add_obstacle([tuple(map(float, a)), tuple(map(float, b))])
        sim.process_obstacles()
        sim.do_step()
        u = np.array(sim.get_agent_velocity(0).to_tuple(), float)
        self.last_velocity = u
        heading, speed = to_unicycle(u)
        if speed < 1e-6:                  # stand still facing where we face
            heading = yaw
        return Plan(force=u, mode="orca", heading=heading, v_ref=speed,
                    obstacles_used=len(rows))


def _preferred(pos: np.ndarray, goal: np.ndarray, v_max: float) -> tuple[float, float]:
    """[m/s] toward the goal at ``v_max``, slowing within ``v_max`` x 1 s of it."""
    d = goal - pos
    dist = math.hypot(*d)
    if dist < 1e-9:
        return 0.0, 0.0
    speed = min(v_max, dist)
    return float(d[0] / dist * speed), float(d[1] / dist * speed)
