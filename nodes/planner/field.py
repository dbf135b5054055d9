"""The shared Artificial Potential Field core (PAPF paper, Szczepanski 2022, Sec. II).

Eq. 2's force (:func:`apf_force`, with extra repulsors: quarks eq. 7, AR-APF eqs. 3-4),
eq. 3's heading (:func:`heading_ref`), eq. 5's speed (:func:`speed_ref`) and our heading
controller (:func:`turn_rate`), N-dimensional and vectorised. Every planner of
``nodes/planner/`` builds on it; the numba kernels match it bit for bit. The reading of
eq. 2's signs: docs/planners.md, "The algorithms in the code".
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

EPS_M = 1e-9  # [m] a point closer than this to the vehicle exerts no force (r = 0 is undefined)


@dataclass(frozen=True)
class APFParams:
    """APF field and motion-law parameters; defaults from PAPF Table 1 unless marked (ours).

    Our choices (d_o, v_max, k_theta, w_max, stagnation watch) are justified in
    docs/planners.md.
    """

    lidar_points: int = 300         # L, LiDAR points per scan (Table 1)
    q_v: float = -1.0               # vehicle charge (Table 1)
    q_o: float = -1.0               # obstacle charge (Table 1)
    q_g: float = 1.0                # goal charge (Table 1)
    k_vg: float = 5.0               # vehicle-goal interaction constant (Table 1)
    k_vo_l: float = 10.0            # k_VO * L: Table 1 gives k_VO = 10 / L
    d_o: float = 0.5                # [m] repulsive effective range (ours)
    theta_err_max_deg: float = 30.0  # [deg] eq. 5 margin orientation error (Table 1)
    v_max: float = 0.1              # [m/s] eq. 4/5 speed limit (ours, from Table 2 speeds)
    k_theta: float = 1.5            # [1/s] heading controller gain (ours)
    w_max: float = 1.0              # [rad/s] heading controller limit (ours)
    scale_to_scan: bool = True      # use L = beams in the actual scan (ours; 300 in the paper)
    stagnation_window_s: float = 20.0   # [s] of scan time without progress -> stagnated (ours)
    stagnation_progress_m: float = 0.1  # [m] progress that resets the window (ours)
    stagnation_roam_m: float = 0.5      # [m] moving this far from where the window began restarts it (ours)
    stagnation_max_s: float = 120.0     # [s] no progress towards the goal for this long -> stagnated (ours)

    @property
    def k_vo(self) -> float:
        """k_VO = 10 / L (Table 1)."""
        return self.k_vo_l / self.lidar_points

    @property
    def theta_err_max(self) -> float:
        """[rad] eq. 5 margin."""
        return math.radians(self.theta_err_max_deg)


class Repulsors(NamedTuple):
    """Extra repulsive particles: ``points`` (K, D), constant ``k``, range ``d_max`` [m], charge ``q``.

    Top quarks (eq. 7: k_VQ, q_Q, d_q), AR-APF virtual walls (k_RW) and obstacles (k_RD).
    """

    points: np.ndarray
    k: float
    d_max: float = math.inf
    q: float = -1.0


def coulomb_sum(pos: np.ndarray, points: np.ndarray, d_max: float = math.inf) -> np.ndarray:
    """``sum r_i / |r_i|^3`` over points with ``EPS_M < |r_i| <= d_max``; ``r_i = points_i - pos``.

    Sequential summation in point order (matches the numba kernel bit for bit).
    """
    pos = np.asarray(pos, dtype=float)
    pts = np.asarray(points, dtype=float).reshape(-1, pos.shape[0])
    if pts.shape[0] == 0:
        return np.zeros_like(pos)
    r = pts - pos
    d2 = r[:, 0] * r[:, 0]
    for j in range(1, pos.shape[0]):
        d2 = d2 + r[:, j] * r[:, j]
    keep = (d2 > EPS_M * EPS_M) & (d2 <= d_max * d_max)
    if not keep.any():
        return np.zeros_like(pos)
    r, d2 = r[keep], d2[keep]
    contrib = r * (1.0 / (d2 * np.sqrt(d2)))[:, None]
    return np.cumsum(contrib, axis=0)[-1]


def apf_force(pos, goal, obstacles, p: APFParams,
              extra: tuple[Repulsors, ...] | list[Repulsors] = ()) -> np.ndarray:
    """Resultant force F_w at ``pos`` (PAPF eq. 2; with ``extra`` eq. 7 / AR-APF eq. 4).

    ``F_goal = -k_VG q_V q_G / |r|^2 * r_hat`` (no range limit); each obstacle point within
    ``d_o`` adds ``-k_VO q_V q_O / |r|^2 * r_hat``; each extra group adds
    ``-k q_V q / |r|^2 * r_hat`` for its points within its ``d_max``. ``goal=None``: no attraction.
    """
    pos = np.asarray(pos, dtype=float)
    force = np.zeros_like(pos)
    if goal is not None:
        force = force - (p.k_vg * p.q_v * p.q_g) * coulomb_sum(pos, np.asarray(goal, float)[None, :])
    force = force - (p.k_vo * p.q_v * p.q_o) * coulomb_sum(pos, obstacles, p.d_o)
    for group in extra:
        force = force - (group.k * p.q_v * group.q) * coulomb_sum(pos, group.points, group.d_max)
    return force


def wrap_angle(a: float) -> float:
    """Angle wrapped to [-pi, pi)."""
    return (a + math.pi) % (2.0 * math.pi) - math.pi


def heading_ref(force) -> float:
    """Eq. 3: theta* = atan2(F_y, F_x) [rad] (quadrant-correct arctan)."""
    return math.atan2(float(force[1]), float(force[0]))


def speed_ref(force_norm: float, theta_err: float, p: APFParams) -> float:
    """Eq. 5: V* = Limit(alpha |F_w|, V_max), alpha = (theta_max - |err|) / theta_max; 0 beyond."""
    err = abs(theta_err)
    if err > p.theta_err_max:
        return 0.0
    alpha = (p.theta_err_max - err) / p.theta_err_max
    return min(alpha * force_norm, p.v_max)


def turn_rate(theta_ref: float, theta: float, p: APFParams) -> float:
    """Heading controller (ours): w = clamp(k_theta * wrap(theta* - theta), +-w_max) [rad/s]."""
    w = p.k_theta * wrap_angle(theta_ref - theta)
    return max(-p.w_max, min(p.w_max, w))
