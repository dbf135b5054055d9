"""PAPF as a planner strategy (Szczepanski et al., IEEE Access 2022, Sec. III, Table 1).

Each cycle predicts a path (Algorithm 1), places top quarks where it stagnates (Sec. III-B)
and steers by eq. 7 towards the temporary goal of eq. 8. Registered as ``papf``: the
planner node and the offline simulations run it through the registry. Our choices where
the paper is silent are switches of :class:`PAPFParams`, off with ``--preset paper``; the
reading step by step: docs/planners.md, "The algorithms in the code".
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nodes.planner.core import Plan, ScanView, Strategy
from nodes.planner.debug import DebugField, Style
from nodes.planner.field import EPS_M, APFParams
from nodes.planner.lazy import lazy_module
from nodes.planner.papf.params import kernel_params
from nodes.planner.papf.settings import PAPF

# the kernels (and numba) load when a PAPF planner is built, not with the registry
kernels = lazy_module("nodes.planner.papf.kernels")
papf_kernel = lazy_module("nodes.planner.papf.compiled")


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
    d_q: float = 2.0                # [m] top-quark range (ours: 2 lambda, see docs)
    quark_ball_m: float = 0.25      # [m] motion law: quark as a charged ball of this radius (ours: lambda_stag)
    tie_tol_m: float = 1e-3         # [m] eq. 8 ties: prefer the farther point along the path (ours)
    use_numba: bool = True          # numba kernel if installed (identical results to numpy)
    persist_quarks: bool = True     # keep quarks (world frame) across cycles (the paper never removes one)
    pull_range_fraction: float = 1.0  # prediction: goal pull as if the goal were <= this * lambda away (ours; 0: literal)
    motion_quarks_within_d_o: bool = True  # motion law: quarks act within d_o (ours; false: within d_q, as the prediction)
    unresolved_global_goal: bool = True    # after M repetitions: eq. 7 with the global goal (ours; false: eq. 8 on the last path)
    stop_at_goal: bool = True       # the prediction stops within Delta of the goal (ours; false: always i_max + n_stag steps)
    quark_restarts_watch: bool = True      # a cycle that places a quark restarts the stagnation watch (ours)
    replace_oldest_quark: bool = True      # beyond M quarks in use the oldest gives way (ours; false: at most M per goal)

    @property
    def i_max(self) -> int:
        """lambda / Delta steps (33 for 1.0 / 0.03; the small epsilon absorbs float error)."""
        return int(math.floor(self.horizon_m / self.step_m + 1e-9))

    @property
    def n_stag(self) -> int:
        """Extra steps for lambda_stag (8 for 0.25 / 0.03)."""
        return int(math.floor(self.stag_fraction * self.horizon_m / self.step_m + 1e-9))

    @property
    def pull_range(self) -> float:
        """[m] Range the prediction's goal pull is evaluated at most at (inf: Algorithm 1 literally)."""
        return self.pull_range_fraction * self.horizon_m if self.pull_range_fraction > 0 else math.inf

    @property
    def stag_radius(self) -> float:
        """R [m]."""
        return self.stag_radius_fraction * self.stag_fraction * self.horizon_m


@dataclass
class Prediction:
    """Algorithm 1's result: the path [m], top quarks [m], abandoned paths, and whether it resolved."""

    path: np.ndarray                 # (n, D) predicted points from the robot, lambda part only
    quarks: np.ndarray               # (Q, D) top quarks in use after this cycle, oldest first
    abandoned: list                  # paths that stagnated
    resolved: bool                   # False: still stagnating after M repetitions
    reached_goal: bool               # the prediction reached the goal


def predict(pos, goal, obstacles, apf: APFParams, pp: PAPFParams, quarks=None) -> Prediction:
    """Algorithm 1 with the top-quark loop of Sec. III-B (``quarks``: already placed ones).

    At most ``M`` repetitions (new quarks) per call and at most ``M`` quarks in use: a new
    quark beyond ``M`` replaces the oldest one. The whole loop is one kernel call
    (:func:`nodes.planner.papf.kernels.predict_paths`).
    """
    dims = len(pos)
    quarks = np.zeros((0, dims)) if quarks is None else np.asarray(quarks, float).reshape(-1, dims)
    if not pp.use_numba:
        # Points beyond (steps * Delta + d_o) can never be within d_o of a predicted point:
        # dropping them changes no result (their terms are skipped anyway), only the time.
        # (The numba kernel does the same, finer, every few steps.)
        reach = (pp.i_max + pp.n_stag) * pp.step_m + apf.d_o + 1e-6
        rel = obstacles - pos
        obstacles = obstacles[np.sum(rel * rel, axis=1) <= reach * reach]
    if not (pp.stop_at_goal and pp.replace_oldest_quark):
        return _predict_loop(pos, goal, obstacles, apf, pp, quarks)
    path, quarks, abandoned, resolved, reached = kernels.predict_paths(
        pos, goal, obstacles, quarks, kernel_params(apf, pp), pp.use_numba)
    return Prediction(path, quarks, abandoned, resolved, reached)


def _predict_loop(pos, goal, obstacles, apf: APFParams, pp: PAPFParams, quarks) -> Prediction:
    """:func:`predict` for the literal switches, the kernel's loop on :func:`rollout`.

    ``stop_at_goal = False`` (Algorithm 1 as written): always ``i_max + n_stag`` steps (stop
    radius 0), so a path that reaches the goal oscillates about it and the stagnation check
    runs there too. ``replace_oldest_quark = False`` (eq. 7's ``0 <= M_curr <= M`` with
    quarks that persist): the quarks already placed all stay and only ``M - M_curr`` more
    may be placed, so once M quarks exist for this goal no repetition is left.
    """
    kp = kernel_params(apf, pp)
    stop = pp.step_m if pp.stop_at_goal else 0.0
    if pp.replace_oldest_quark:
        quarks = quarks[max(0, quarks.shape[0] - pp.max_quarks):]
        budget = pp.max_quarks
    else:
        budget = pp.max_quarks - quarks.shape[0]
    abandoned = []
    while True:
        path, reached = kernels.rollout(pos, goal, obstacles, quarks, kp, kp.i_max + kp.n_stag, stop,
                                        pp.use_numba)
        if reached:
            return Prediction(path, quarks, abandoned, True, True)
        main = path[: kp.i_max + 1]
        stuck, mean = kernels.tail_stagnation(path, kp.i_max + 1, kp.stag_radius, pp.use_numba)
        if not stuck:
            return Prediction(main, quarks, abandoned, True, False)
        if len(abandoned) >= budget:
            return Prediction(main, quarks, abandoned, False, False)
        abandoned.append(main)
        kept = quarks[max(0, quarks.shape[0] - pp.max_quarks + 1):] if pp.replace_oldest_quark else quarks
        quarks = np.vstack([kept, mean])


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


def quark_force(pos, quarks: np.ndarray, apf: APFParams, pp: PAPFParams) -> np.ndarray:
    """Eq. 7's top-quark term at ``pos`` with each quark a uniformly charged ball (motion law).

    Quarks act within d_o here (the range eq. 7's where-clause names; the prediction uses
    d_q): a quark a metre behind the robot must not shove it into the obstacles beside it.
    Outside ``quark_ball_m`` (and within d_o) this is eq. 7 exactly, ``-k_VQ q_V q_Q / |r|^2
    r_hat``; inside, the push falls linearly to 0 at the centre (Gauss's law for a ball), so
    a quark placed where the robot itself stagnated cannot produce an unbounded push.
    """
    pos = np.asarray(pos, dtype=float)
    force = np.zeros_like(pos)
    if len(quarks) == 0:
        return force
    kp = kernel_params(apf, pp)
    r = np.asarray(quarks, dtype=float) - pos
    dist = np.sqrt(np.sum(r * r, axis=1))
    keep = (dist > EPS_M) & (dist <= kp.q_lim)
    soft = np.maximum(dist[keep], kp.ball)
    return force - kp.g_q * np.sum(r[keep] / (soft ** 3)[:, None], axis=0)


#: ``--preset paper``: Algorithm 1 and Sec. III as written, every deviation above off: quarks
#: kept, at most M per goal (eq. 7: 0 <= M_curr <= M), one quark field (range d_q) for
#: prediction and motion. d_q keeps its value (no value in the paper, like d_o).
PAPER_PRESET = {"pull_range_fraction": 0.0, "motion_quarks_within_d_o": False, "quark_ball_m": 0.0,
                "unresolved_global_goal": False, "stop_at_goal": False,
                "quark_restarts_watch": False, "replace_oldest_quark": False, "tie_tol_m": 0.0}


class PAPFStrategy(Strategy):
    """PAPF on the shared APF core (registered as ``papf``)."""

    name = "papf"
    rank = 1
    roles = ("compared", "traffic", "crowd", "papf-proposed")
    colour, colour_map = "tab:orange", "Oranges"
    Params = PAPFParams
    SPECS = PAPF
    PAPER_PRESET = PAPER_PRESET
    DEBUG = (
        DebugField("top_quarks", "points", unit="m", label="top quark",
                   doc="top quarks in use (Sec. III-B; their push: eq. 7)",
                   style=Style((0.84, 0.15, 0.16, 0.9), 0.12)),
        DebugField("abandoned_paths", "paths", unit="m", label="abandoned prediction",
                   doc="this cycle's predictions that stagnated (Algorithm 1)",
                   style=Style((0.5, 0.5, 0.5, 0.5), 0.015, dashed=True)),
    )

    def __init__(self, params: PAPFParams | None = None):
        self.params = params or PAPFParams()
        self.quarks = None
        # loads the kernels now (numba with them), in the thread that builds the planner
        self.uses_numba = self.params.use_numba and kernels.HAVE_NUMBA

    def reset(self) -> None:
        """Drop the top quarks (a new goal)."""
        self.quarks = None

    def warm_up(self, apf: APFParams) -> None:
        """Compile the kernels (numba) before the node declares itself ready."""
        predict(np.zeros(2), np.array([1.0, 0.0]), np.array([[0.5, 0.1]]), apf, self.params)
        if self.params.use_numba and kernels.HAVE_NUMBA:   # the literal switches' loop (rollout, tail)
            _predict_loop(np.zeros(2), np.array([1.0, 0.0]), np.array([[0.5, 0.1]]), apf,
                          self.params, np.zeros((0, 2)))
        if self.params.use_numba and kernels.HAVE_NUMBA:   # the compiled cycle, with and without quarks
            for quarks in (None, np.array([[0.4, 0.3]])):
                papf_kernel.plan_compiled(np.zeros(2), np.array([1.0, 0.0]), np.array([[0.5, 0.1]]), apf,
                              self.params, quarks)
        kernels.field_force(np.zeros(2), np.array([1.0, 0.0]), np.array([[0.5, 0.1]]),
                            kernel_params(apf, self.params), self.params.use_numba)

    def plan(self, pos: np.ndarray, yaw: float, goal: np.ndarray, view: ScanView,
             apf: APFParams) -> Plan:
        """Prediction, top quarks and eq. 8's temporary goal, then eq. 7's force at ``pos`` [m]."""
        pp = self.params
        obstacles = view.points
        kept = self.quarks if pp.persist_quarks else None
        if pp.use_numba and kernels.HAVE_NUMBA and pp.stop_at_goal and len(pos) == 2:
            return self._plan_compiled(pos, goal, obstacles, apf, kept)
        pred = predict(pos, goal, obstacles, apf, pp, kept)
        self.quarks = pred.quarks
        kp = kernel_params(apf, pp)
        if pred.resolved or not pp.unresolved_global_goal:       # eq. 2: the direction line
            f_apf = kernels.field_force(pos, goal, obstacles, kp, pp.use_numba)
            direction = f_apf if np.linalg.norm(f_apf) > 0 else goal - pos
            target = temporary_goal(pos, direction, pred.path, pp.tie_tol_m)
            mode = ("bypass" if pred.quarks.shape[0] else "drive") if pred.resolved else "unresolved"
        else:   # no stagnation-free path after M repetitions: eq. 7 with the global goal
            target, mode = goal, "unresolved"
        force = (kernels.field_force(pos, target, obstacles, kp, pp.use_numba)
                 + quark_force(pos, pred.quarks, apf, pp))
        return Plan(force=force, mode=mode, temporary_goal=tuple(target[:2]),
                    predicted_path=pred.path,
                    debug={"top_quarks": pred.quarks, "abandoned_paths": pred.abandoned},
                    searching=bool(pred.abandoned) and pp.quark_restarts_watch)

    def _plan_compiled(self, pos, goal, obstacles, apf: APFParams, kept) -> Plan:
        """:meth:`plan` in two kernel calls (:func:`nodes.planner.papf.compiled.plan_compiled`)."""
        pp = self.params
        out = papf_kernel.plan_compiled(pos, goal, obstacles, apf, pp, kept)
        path, quarks, abandoned, resolved, target, force = out
        self.quarks = quarks
        if resolved:
            mode = "bypass" if quarks.shape[0] else "drive"
        else:
            mode = "unresolved"
        return Plan(force=force, mode=mode, temporary_goal=tuple(target[:2]),
                    predicted_path=path, debug={"top_quarks": quarks, "abandoned_paths": abandoned},
                    searching=len(abandoned) > 0 and pp.quark_restarts_watch)
