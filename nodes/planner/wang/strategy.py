"""Wang's improved APF (``wang``, eqs. 6-8) and his traditional APF (``wang-apf``, eqs. 1-5)
as planner strategies, on N-dimensional points (2-D in the node, 3-D in papf/offline/point3d.py).

Wang's eqs. 6-8 mix up their distances; our reading, and the control point ahead of the
robot (ours): docs/planners.md, "The algorithms in the code" and its Wang section.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from common.errors import ConfigError
from nodes.planner.core import Plan, ScanView, Strategy
from nodes.planner.field import EPS_M, APFParams
from nodes.planner.settings import attraction_ratio, require_ratio
from nodes.planner.wang.settings import WANG, WANG_APF, WANG_RATIO_MAX


@dataclass(frozen=True)
class WangParams:
    """Wang's gains scaled to a LiDAR robot (Table 1 values were for a 10 m MATLAB map)."""

    k_att: float = 10.0             # attraction gain k_att (Wang Table 1)
    k_rep_l: float = 5.0            # k_rep * L: per-point repulsion gain times beams (ours)
    lidar_points: int = 300         # L used to scale k_rep (PAPF Table 1)
    rho_0: float = 0.5              # [m] influence radius (ours: = APF d_o); rho_1 = 2 rho_0
    r_0: float = 0.0                # [m] obstacle radius R_0 in eta (0: LiDAR points)
    control_offset_m: float = 0.05  # [m] force evaluated this far ahead of the robot, 2-D (ours)

    def __post_init__(self):
        for name in ("k_att", "k_rep_l", "r_0", "control_offset_m"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise ConfigError(f"wang setting {name} = {value!r}: expected a finite number >= 0")
        if not (math.isfinite(self.rho_0) and self.rho_0 > 0):
            raise ConfigError(f"wang setting rho_0 = {self.rho_0!r} m: expected a finite number > 0")
        if self.lidar_points < 1:
            raise ConfigError(f"wang setting lidar_points = {self.lidar_points!r}: expected >= 1")

    @property
    def k_rep(self) -> float:
        """Per-point repulsion gain k_rep = k_rep_l / L."""
        return self.k_rep_l / self.lidar_points

    @property
    def rho_1(self) -> float:
        """Double influence radius rho_1 = 2 rho_0 [m] (eq. 8)."""
        return 2.0 * self.rho_0


def eta(rho_min: float, wp: WangParams) -> float:
    """Eq. 6 dynamic attraction coefficient: 0 within R_0, sine up to 1 at R_0 + rho_0, then 1.

    ``rho_min`` [m]: distance to the nearest obstacle point (our X_0).
    """
    if rho_min >= wp.r_0 + wp.rho_0:
        return 1.0
    x = max(rho_min - wp.r_0, 0.0) / wp.rho_0
    return 0.5 * (math.sin(x * math.pi - math.pi / 2) + 1.0)


def lambda_goal(d_goal: float, wp: WangParams) -> float:
    """Target part of eq. 8's lambda: 0 at the target, cosine up to 1 at rho_1, then 1."""
    return 0.5 * (1.0 - math.cos(math.pi * min(d_goal / wp.rho_1, 1.0)))


def lambda_obs(rho: np.ndarray, wp: WangParams) -> np.ndarray:
    """Obstacle part of eq. 8's lambda: 1 inside rho_0, cosine down to 0 at rho_1, 0 beyond."""
    taper = 0.5 * (np.cos((rho - wp.rho_0) / wp.rho_0 * math.pi) + 1.0)
    return np.where(rho < wp.rho_0, 1.0, np.where(rho < wp.rho_1, taper, 0.0))


def attraction_coef(rho_min: float, d_goal: float, wp: WangParams) -> float:
    """eta_eff = 1 - lambda_goal (1 - eta): eta away from the target, 1 at the target."""
    return 1.0 - lambda_goal(d_goal, wp) * (1.0 - eta(rho_min, wp))


def wang_force(pos, goal, obstacles, wp: WangParams) -> np.ndarray:
    """Resultant force at ``pos`` (any dimension D): attraction + repulsion as the module doc."""
    pos = np.asarray(pos, dtype=float)
    goal = np.asarray(goal, dtype=float)
    pts = np.asarray(obstacles, dtype=float).reshape(-1, pos.shape[0])
    away = pos - pts
    rho = np.sqrt(np.sum(away * away, axis=1))
    keep = rho > EPS_M
    away, rho = away[keep], rho[keep]
    rho_min = float(rho.min()) if rho.size else math.inf
    to_goal = goal - pos
    d_goal = float(np.sqrt(np.sum(to_goal * to_goal)))
    f_att = wp.k_att * attraction_coef(rho_min, d_goal, wp) * to_goal
    near = rho < wp.rho_1
    if not near.any():
        return f_att
    r, a = rho[near], away[near]
    mag = lambda_obs(r, wp) * wp.k_rep * (1.0 / r - 1.0 / wp.rho_1) / r**2
    f_rep = lambda_goal(d_goal, wp) * np.sum(a * (mag / r)[:, None], axis=0)
    return f_att + f_rep


def control_point(pos, yaw: float, goal, wp: WangParams) -> np.ndarray:
    """The point the force acts on: in 2-D ``min(control_offset_m, d_g / 2)`` ahead along the
    heading (half the goal distance at most, so the point cannot settle on the target while
    the robot stays away); in other dimensions (a point robot) ``pos`` itself."""
    pos = np.asarray(pos, dtype=float)
    if pos.shape[0] != 2 or wp.control_offset_m == 0:
        return pos
    offset = min(wp.control_offset_m, 0.5 * float(np.linalg.norm(np.asarray(goal) - pos)))
    return pos + offset * np.array([math.cos(yaw), math.sin(yaw)])


def scaled_to_scan(wp, apf: APFParams):
    """``wp`` with its ``lidar_points`` set to the scan's when the gains scale to the scan
    (``apf.scale_to_scan``): Wang's per-obstacle gains spread over the beams actually seen."""
    if apf.scale_to_scan and apf.lidar_points != wp.lidar_points:
        return dataclasses.replace(wp, lidar_points=apf.lidar_points)
    return wp


class WangStrategy(Strategy):
    """Wang's improved APF (registered as ``wang``)."""

    name = "wang"
    rank = 3
    roles = ("compared", "wang-proposed")
    colour, colour_map = "tab:brown", "Greens"
    Params = WangParams
    SPECS = WANG
    #: ``--preset paper``: the force at the robot itself (Wang moves a point along it).
    PAPER_PRESET = {"control_offset_m": 0.0}

    @classmethod
    def check_strength(cls, apf, params) -> None:
        """The goal's pull ``k_att / k_rep_l`` at most its measured ceiling."""
        require_ratio("k_att/k_rep_l", attraction_ratio(apf, params), WANG_RATIO_MAX)

    def plan(self, pos: np.ndarray, yaw: float, goal: np.ndarray, view: ScanView,
             apf: APFParams) -> Plan:
        """Eqs. 6-8 at the control point ahead of ``pos`` [m]."""
        wp = scaled_to_scan(self.params, apf)
        at = control_point(pos, yaw, goal, wp)
        return Plan(force=wang_force(at, goal, view.points, wp))


@dataclass(frozen=True)
class WangAPFParams:
    """Wang's traditional APF (eqs. 1-5), gains of Table 1 per LiDAR point."""

    k_att: float = 10.0             # K_att (Wang Table 1)
    k_rep_l: float = 2.0            # K_rep * L: Table 1's K_rep = 2 per obstacle, spread over the beams
    lidar_points: int = 300         # L used to scale k_rep
    rho_0: float = 0.5              # [m] influence radius (ours, = d_o; Table 1's 20 is in map units)


def traditional_force(pos, goal, obstacles, wp: WangAPFParams) -> np.ndarray:
    """Eqs. 2 and 4: ``K_att (X_g - X_u)`` plus, per point within rho_0,
    ``k_rep (1/rho - 1/rho_0) / rho^2`` away from it (eq. 2's convention: factor 2 dropped)."""
    pos = np.asarray(pos, dtype=float)
    force = wp.k_att * (np.asarray(goal, dtype=float) - pos)
    away = pos - np.asarray(obstacles, dtype=float).reshape(-1, pos.shape[0])
    rho = np.sqrt(np.sum(away * away, axis=1))
    near = (rho > EPS_M) & (rho < wp.rho_0)
    if near.any():
        r = rho[near]
        mag = (wp.k_rep_l / wp.lidar_points) * (1.0 / r - 1.0 / wp.rho_0) / r**2
        force = force + np.sum(away[near] * (mag / r)[:, None], axis=0)
    return force


class WangAPFStrategy(Strategy):
    """Wang's traditional APF baseline, eqs. 1-5 (registered as ``wang-apf``)."""

    name = "wang-apf"
    rank = 4
    roles = ("wang-baseline",)
    Params = WangAPFParams
    SPECS = WANG_APF
    PAPER_PRESET: dict = {}   # eqs. 1-5 as written

    def plan(self, pos: np.ndarray, yaw: float, goal: np.ndarray, view: ScanView,
             apf: APFParams) -> Plan:
        """Eqs. 2 and 4 at ``pos`` [m] (the traditional APF)."""
        return Plan(force=traditional_force(pos, goal, view.points, scaled_to_scan(self.params, apf)))
