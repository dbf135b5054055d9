"""Improved APF of G. Wang, "Real-time path planning based on improved artificial potential
field method" (papers/improved-apf-wang.txt), on N-dimensional points (2-D and 3-D).

The paper's eqs. 6-8 mix up their distances (the text and the formulas disagree); this is
our reconstruction, kept to what the text says each term must do (docs/planners.md):

- **Attraction** (eqs. 6-7): ``F_att = k_att * eta * (X_g - X_u)`` (quadratic potential,
  linear force). ``eta`` (dynamic attraction coefficient) =
  ``(sin((rho_min - R_0) / rho_0 * pi - pi/2) + 1) / 2`` while the nearest obstacle point
  (our X_0, the potential local-minimum point) is within ``R_0 .. R_0 + rho_0``
  (rho_min = distance to it; R_0 = 0 for LiDAR points), else 1: the pull fades smoothly
  near obstacles instead of balancing them. Within rho_1 of the goal eta = 1 (the goal
  is the minimum we want).
- **Repulsion** (eq. 8): each point at distance ``rho < rho_1 = 2 rho_0`` pushes with
  ``lambda_obs(rho) * lambda_goal(d_g) * k_rep * (1/rho - 1/rho_1) / rho^2`` along the
  point->robot direction. ``lambda_obs`` is the paper's cosine,
  ``(cos((rho - rho_0) / rho_0 * pi) + 1) / 2`` on ``rho_0 .. rho_1`` (1 inside rho_0,
  0 beyond rho_1: the repulsion fades out smoothly); ``lambda_goal`` =
  ``(1 - cos(pi * min(d_g / rho_0, 1))) / 2`` makes the repulsion vanish at the target
  (the paper's fix for a goal next to an obstacle).

The planner core then applies the PAPF paper's eqs. 3 and 5 to the force.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nodes.planner.apf import EPS_M, APFParams
from nodes.planner.core import Plan, ScanView


@dataclass(frozen=True)
class WangParams:
    """Wang's gains scaled to a LiDAR robot (Table 1 values were for a 10 m MATLAB map)."""

    k_att: float = 10.0             # attraction gain (Wang Table 1)
    k_rep_l: float = 5.0            # k_rep * L: per-point repulsion gain times beams (ours)
    lidar_points: int = 300         # L used to scale k_rep (PAPF Table 1)
    rho_0: float = 0.5              # [m] influence radius (ours: = APF d_o); rho_1 = 2 rho_0
    r_0: float = 0.0                # [m] obstacle radius R_0 in eta (0: LiDAR points)

    @property
    def k_rep(self) -> float:
        return self.k_rep_l / self.lidar_points

    @property
    def rho_1(self) -> float:
        """Double influence radius rho_1 = 2 rho_0 [m]."""
        return 2.0 * self.rho_0


def eta(rho_min: float, wp: WangParams) -> float:
    """Dynamic attraction coefficient (eq. 6), 0 at R_0 rising to 1 at R_0 + rho_0."""
    if rho_min >= wp.r_0 + wp.rho_0:
        return 1.0
    x = max(rho_min - wp.r_0, 0.0) / wp.rho_0
    return 0.5 * (math.sin(x * math.pi - math.pi / 2) + 1.0)


def lambda_goal(d_goal: float, wp: WangParams) -> float:
    """Goal factor of the repulsion: 0 at the target, 1 from rho_0 on."""
    return 0.5 * (1.0 - math.cos(math.pi * min(d_goal / wp.rho_1, 1.0)))


def lambda_obs(rho: np.ndarray, wp: WangParams) -> np.ndarray:
    """Eq. 8 taper: 1 inside rho_0, cosine to 0 at rho_1, 0 beyond."""
    taper = 0.5 * (np.cos((rho - wp.rho_0) / wp.rho_0 * math.pi) + 1.0)
    return np.where(rho < wp.rho_0, 1.0, np.where(rho < wp.rho_1, taper, 0.0))


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
    f_att = wp.k_att * (eta(rho_min, wp) if d_goal >= wp.rho_1 else 1.0) * to_goal
    near = rho < wp.rho_1
    if not near.any():
        return f_att
    r, a = rho[near], away[near]
    mag = lambda_obs(r, wp) * wp.k_rep * (1.0 / r - 1.0 / wp.rho_1) / r**2
    f_rep = lambda_goal(d_goal, wp) * np.sum(a * (mag / r)[:, None], axis=0)
    return f_att + f_rep


class WangStrategy:
    """Wang's improved APF (registered as ``wang``)."""

    name = "wang"
    Params = WangParams

    def __init__(self, params: WangParams | None = None):
        self.params = params or WangParams()

    def reset(self) -> None:
        pass

    def plan(self, pos: np.ndarray, yaw: float, goal: np.ndarray, view: ScanView,
             apf: APFParams) -> Plan:
        wp = self.params
        if apf.scale_to_scan and apf.lidar_points != wp.lidar_points:
            wp = WangParams(wp.k_att, wp.k_rep_l, apf.lidar_points, wp.rho_0, wp.r_0)
        return Plan(force=wang_force(pos, goal, view.points, wp))
