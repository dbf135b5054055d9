"""The social-force model as a planner strategy (``--planner social_force``).

The robot is one more pedestrian of ``pysocialforce`` (the Extended Social Force model:
Helbing & Molnár 1995, "Social force model for pedestrian dynamics"; the pedestrian
interaction of Moussaïd et al. 2009; the library's own constants) for one step per control
cycle: its desired force pulls it toward a point 1 m ahead on the way to the goal at
``v_max`` with the strength a pedestrian's has at walking speed (relaxation time
``relaxation_s`` x ``v_max`` / 1.34 m/s: the library's forces are a pedestrian's, and a
robot ten times slower would otherwise be held by every wall force), the tracked people and robots push it by the
library's social force (they move: the interaction looks at their velocities), the groups
among them (:mod:`nodes.planner.neighbours`) by the same as one agent each, and every scan
point within ``obstacle_range_m`` - walls, boxes and the people's bodies, which the library's
point pedestrians do not have - by its obstacle force (``obstacle_factor``,
``obstacle_sigma_m``; the robot's radius its circumscribed disc + ``safety_m``). The new
velocity ``v + dt F`` (capped at ``v_max``) is tracked on the ROSbot's unicycle as ORCA's is
(:mod:`nodes.planner.orca.strategy`: heading = its direction, speed = its size x cos(heading
error), turn rate from the shared heading controller).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nodes.planner.core import Plan, ScanView, Strategy
from nodes.planner.field import APFParams
from nodes.planner.neighbours import agents, robot_radius, to_unicycle, with_groups
from nodes.planner.social_force.settings import SOCIAL_FORCE

CARROT_M = 1.0          # [m] the desired force's goal: this far ahead toward the goal
STEP_S = 0.1            # [s] the control period
MULTIPLIER = 1.3        # [-] pysocialforce's max_speed_multiplier (its default)
GROUP_POINT_STEP_M = 0.1   # [m] a group's disc as obstacle points this far apart
PEDESTRIAN_SPEED_M_S = 1.34   # [m/s] Helbing & Molnár's mean desired walking speed


@dataclass(frozen=True)
class SocialForceParams:
    """The social-force planner's settings (module doc); defaults are the library's."""

    relaxation_s: float = 0.5          # [s] tau of the desired force
    social_factor: float = 5.1         # [-] the social force's factor
    obstacle_factor: float = 10.0      # [-] the obstacle force's factor
    obstacle_sigma_m: float = 0.2      # [m] its decay length
    safety_m: float = 0.05             # [m] added to the robot's circumscribed radius
    obstacle_range_m: float = 3.0      # [m] scan points pushing the robot
    neighbor_dist_m: float = 10.0      # [m] tracked agents considered
    group_gap_m: float = 0.6           # [m] people closer than this, moving alike: a group


class SocialForceStrategy(Strategy):
    """Social force (module doc)."""

    name = "social_force"
    rank = 7
    roles = ("crowd",)
    colour, colour_map = "tab:cyan", "PuBu"
    uses_objects = True
    needs_blas = True    # pysocialforce's numba kernels use np.dot: the node keeps scipy
    Params = SocialForceParams
    SPECS = SOCIAL_FORCE

    def __init__(self, params=None):
        super().__init__(params)
        self._tracks: tuple = ()
        self._v = 0.0
        self._sim = None
        self.last_velocity = np.zeros(2)

    def observe(self, objects: tuple, road, t: float, v: float) -> None:
        self._tracks, self._v = tuple(objects), v

    def warm_up(self, apf: APFParams) -> None:
        """Import the library and compile its kernels (a first force) before the node is
        ready: the first cycle's compile would outlast the driver's lockstep timeout."""
        sim = self._simulator(np.array([[0.0, 0.0, 0.1, 0.0, 1.0, 0.0],
                                        [1.0, 0.5, -0.5, 0.0, 0.0, 0.5]]), apf)
        sim.env._obstacles = [np.array([[0.5, -0.5], [0.6, -0.5]])]
        with np.errstate(invalid="ignore", divide="ignore"):
            sim.compute_forces()
        del sim.peds.ped_states[:-1], sim.peds.group_states[:-1]

    def plan(self, pos: np.ndarray, yaw: float, goal: np.ndarray, view: ScanView,
             apf: APFParams) -> Plan:
        """One social-force step (module doc): the heading and speed to track."""
        prm = self.params
        rows = with_groups(agents(self._tracks, pos, prm.neighbor_dist_m), prm.group_gap_m)
        d = goal - pos
        dist = max(math.hypot(*d), 1e-9)
        carrot = pos + d / dist * max(CARROT_M, 0.0)
        own = (self._v * math.cos(yaw), self._v * math.sin(yaw))
        state = np.vstack([[*pos, *own, *carrot],
                           np.column_stack([rows[:, :2], rows[:, 2:4],
                                            rows[:, :2] + rows[:, 2:4]])])
        sim = self._simulator(state, apf)
        sim.env._obstacles = self._obstacles(view, pos, rows)
        with np.errstate(invalid="ignore", divide="ignore"):   # 0/0 speeds: its own guard
            force = np.nan_to_num(sim.compute_forces()[0])
        del sim.peds.ped_states[:-1], sim.peds.group_states[:-1]   # the library keeps history
        u = np.asarray(own) + STEP_S * force
        speed = math.hypot(*u)
        if speed > apf.v_max:
            u *= apf.v_max / speed
        # within a step of the goal: no faster than reaches it (the desired force is a carrot's)
        if dist < apf.v_max * STEP_S * 10 and math.hypot(*u) > dist:
            u *= dist / math.hypot(*u)
        self.last_velocity = u
        heading, v_ref = to_unicycle(u)
        if v_ref < 1e-6:
            heading = yaw
        return Plan(force=u, mode="social_force", heading=heading, v_ref=v_ref,
                    obstacles_used=len(rows))

    def _simulator(self, state: np.ndarray, apf: APFParams):
        """The library's simulator with this cycle's state and our settings."""
        from common.crowd import load_pysocialforce

        prm = self.params
        if self._sim is None:
            self._sim = load_pysocialforce().Simulator(state.copy(), obstacles=None)
        sim = self._sim
        sim.peds.update(state.copy(), [])
        speeds = np.concatenate([[apf.v_max], np.hypot(state[1:, 2], state[1:, 3])])
        sim.peds.initial_speeds = speeds / MULTIPLIER
        sim.peds.max_speed_multiplier = MULTIPLIER
        sim.peds.max_speeds = speeds
        sim.peds.agent_radius = robot_radius(prm.safety_m)
        for f in sim.forces:
            kind = type(f).__name__
            if kind == "DesiredForce":   # a pedestrian's pull, at the robot's speed (module doc)
                f.config.config["relaxation_time"] = prm.relaxation_s * apf.v_max \
                    / PEDESTRIAN_SPEED_M_S
            elif kind == "SocialForce":
                f.factor = prm.social_factor
            elif kind == "ObstacleForce":
                f.factor = prm.obstacle_factor
                f.config.config["sigma"] = prm.obstacle_sigma_m
        return sim

    def _obstacles(self, view: ScanView, pos: np.ndarray, rows: np.ndarray) -> list:
        """The scan points within range, and every group's disc as points (module doc)."""
        pts = view.points
        near = pts[np.hypot(*(pts - pos).T) <= self.params.obstacle_range_m] if len(pts) \
            else np.zeros((0, 2))
        out = [near] if len(near) else []
        n_agents = len(agents(self._tracks, pos, self.params.neighbor_dist_m))
        for x, y, _, _, r in rows[n_agents:]:          # the groups' discs
            k = max(8, math.ceil(2 * math.pi * r / GROUP_POINT_STEP_M))
            a = np.arange(k) * (2 * math.pi / k)
            out.append(np.column_stack([x + r * np.cos(a), y + r * np.sin(a)]))
        return out
