"""Predictive APF (Szczepanski et al., IEEE Access 2022, Sec. III; Table 1 parameters).

One cycle (:meth:`PAPFStrategy.plan`):

1. **Prediction** (Algorithm 1): from the robot, step ``Delta`` along the eq. 7 force
   towards the *global* goal for ``i_max = lambda / Delta`` steps, plus ``lambda_stag /
   Delta`` more for the stagnation check (:func:`predict`).
2. **Top quarks** (Sec. III-B): if all the extra ``lambda_stag`` points lie within ``R`` of
   their mean, the prediction stagnated: put a top quark (k_VQ = 5 k_VO, q_Q = -1, range
   d_q) at that mean, keep the path as *abandoned* and predict again; at most ``M`` quarks.
3. **Temporary goal** (Sec. III-C, eq. 8): the predicted point farthest from the line
   through the robot along the classic APF force (eq. 2 at the robot).
4. **Motion** (Sec. III-D): the eq. 7 force with the temporary goal in place of the global
   one (obstacles + this cycle's quarks); the planner core turns it into (v, w) by eqs. 3, 5.

Choices where the paper is silent (docs/planners.md): quarks persist in the world frame
while they can reach the prediction; d_q = 1.0 m; the prediction stops at the goal (no
stagnation check then); ties in eq. 8 go to the farthest point along the path; after M
quarks the last (stagnating) path is used as is (mode ``unresolved``) and the planner's
progress watch decides stagnation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nodes.planner.apf import APFParams, Repulsors, apf_force
from nodes.planner.core import Plan, ScanView
from nodes.planner.kernels import rollout, tail_stagnation


@dataclass(frozen=True)
class PAPFParams:
    """PAPF Table 1 parameters (and our documented choices)."""

    horizon_m: float = 1.0          # lambda, horizon of prediction (Table 1)
    step_m: float = 0.03            # Delta, prediction step (Table 1)
    stag_fraction: float = 0.25     # lambda_stag = 0.25 lambda (Table 1)
    stag_radius_fraction: float = 0.25  # R = 0.25 lambda_stag (Table 1)
    k_vq_factor: float = 5.0        # k_VQ = 5 k_VO (Table 1)
    q_q: float = -1.0               # top quark charge (Table 1)
    max_quarks: int = 10            # M (Table 1)
    d_q: float = 1.0                # [m] top-quark range (ours: = lambda; d_q = d_o fails, see docs)
    tie_tol_m: float = 1e-3         # [m] eq. 8 ties: prefer the farther point along the path (ours)
    use_numba: bool = True          # numba kernel if installed (identical results to numpy)
    persist_quarks: bool = True     # keep quarks (world frame) across cycles while in reach (ours)

    @property
    def i_max(self) -> int:
        """lambda / Delta steps (33 for 1.0 / 0.03; the small epsilon absorbs float error)."""
        return int(math.floor(self.horizon_m / self.step_m + 1e-9))

    @property
    def n_stag(self) -> int:
        """Extra steps for lambda_stag (8 for 0.25 / 0.03)."""
        return int(math.floor(self.stag_fraction * self.horizon_m / self.step_m + 1e-9))

    @property
    def stag_radius(self) -> float:
        """R [m]."""
        return self.stag_radius_fraction * self.stag_fraction * self.horizon_m


@dataclass
class Prediction:
    path: np.ndarray                 # (n, D) predicted points from the robot, lambda part only
    quarks: np.ndarray               # (Q, D) top quarks placed this cycle
    abandoned: list                  # paths that stagnated
    resolved: bool                   # False: still stagnating after M quarks
    reached_goal: bool               # the prediction reached the goal


def predict(pos, goal, obstacles, apf: APFParams, pp: PAPFParams, quarks=None) -> Prediction:
    """Algorithm 1 with the top-quark loop of Sec. III-B (``quarks``: already placed ones)."""
    g_goal = apf.k_vg * apf.q_v * apf.q_g
    g_obs = apf.k_vo * apf.q_v * apf.q_o
    g_q = pp.k_vq_factor * apf.k_vo * apf.q_v * pp.q_q
    d_q = pp.d_q
    quarks = np.zeros((0, len(pos))) if quarks is None else np.asarray(quarks, float).reshape(-1, len(pos))
    # Points beyond (steps * Delta + d_o) can never be within d_o of a predicted point:
    # dropping them changes no result (their terms are skipped anyway), only the time.
    reach = (pp.i_max + pp.n_stag) * pp.step_m + apf.d_o + 1e-6
    rel = obstacles - pos
    obstacles = obstacles[np.sum(rel * rel, axis=1) <= reach * reach]
    abandoned = []
    while True:
        path, reached = rollout(pos, goal, g_goal, obstacles, g_obs, apf.d_o, quarks, g_q, d_q,
                                pp.step_m, pp.i_max + pp.n_stag, pp.step_m, pp.use_numba)
        if reached:
            return Prediction(path, quarks, abandoned, True, True)
        main = path[: pp.i_max + 1]
        stuck, mean = tail_stagnation(path, pp.i_max + 1, pp.stag_radius, pp.use_numba)
        if not stuck:
            return Prediction(main, quarks, abandoned, True, False)
        if quarks.shape[0] >= pp.max_quarks:
            return Prediction(main, quarks, abandoned, False, False)
        abandoned.append(main)
        quarks = np.vstack([quarks, mean])


def temporary_goal(pos, direction, path: np.ndarray, tie_tol: float) -> np.ndarray:
    """Eq. 8: the path point farthest from the line through ``pos`` along ``direction``.

    The distance |A x + B y + C| / sqrt(A^2 + B^2) equals the norm of the component of
    ``p - pos`` normal to the line (used here, valid in N-D). The robot's own point
    (index 0) is excluded; among points within ``tie_tol`` of the maximum the last one wins.
    """
    pts = path[1:] if path.shape[0] > 1 else path
    u = np.asarray(direction, dtype=float)
    u = u / np.linalg.norm(u)
    rel = pts - pos
    normal = rel - np.outer(rel @ u, u)
    dist = np.sqrt(np.sum(normal * normal, axis=1))
    best = np.flatnonzero(dist >= dist.max() - tie_tol)[-1]
    return pts[best]


class PAPFStrategy:
    """PAPF on the shared APF core (registered as ``papf``)."""

    name = "papf"
    Params = PAPFParams

    def __init__(self, params: PAPFParams | None = None):
        self.params = params or PAPFParams()
        self.quarks = None

    def reset(self) -> None:
        self.quarks = None

    def warm_up(self, apf: APFParams) -> None:
        """Compile the kernel (numba) before the node declares itself ready."""
        predict(np.zeros(2), np.array([1.0, 0.0]), np.array([[0.5, 0.1]]), apf, self.params)

    def plan(self, pos: np.ndarray, yaw: float, goal: np.ndarray, view: ScanView,
             apf: APFParams) -> Plan:
        pp = self.params
        obstacles = view.points
        kept = None
        if pp.persist_quarks and self.quarks is not None and len(self.quarks):
            reach = (1 + pp.stag_fraction) * pp.horizon_m + pp.d_q
            kept = self.quarks[np.hypot(*(self.quarks - pos).T) <= reach]
        pred = predict(pos, goal, obstacles, apf, pp, kept)
        self.quarks = pred.quarks
        f_apf = apf_force(pos, goal, obstacles, apf)          # eq. 2: the direction line
        direction = f_apf if np.linalg.norm(f_apf) > 0 else goal - pos
        temp = temporary_goal(pos, direction, pred.path, pp.tie_tol_m)
        quarks = Repulsors(pred.quarks, pp.k_vq_factor * apf.k_vo, pp.d_q, pp.q_q)
        force = apf_force(pos, temp, obstacles, apf, extra=(quarks,))   # eq. 7, temporary goal
        mode = "drive" if pred.resolved else "unresolved"
        if pred.quarks.shape[0] and pred.resolved:
            mode = "bypass"
        return Plan(force=force, mode=mode, temporary_goal=tuple(temp[:2]),
                    predicted_path=pred.path, abandoned_paths=pred.abandoned,
                    top_quarks=pred.quarks)
