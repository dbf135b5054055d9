"""AR-APF: APF supported by augmented reality (Szczepanski, Energies 2021, 14, 6642).

Per cycle (:meth:`ARAPFStrategy.plan`), on the shared APF core with the paper's own
constants (Table 1: k_RT = 5, k_RO = 5/L, no repulsion range):

1. **Detection** (Sec. 3.1, :func:`detect_minimum`): the beams within +-alpha of the goal
   direction that return closer than d_min block; if no free run between blocking
   returns is at least s_min wide, a local minimum lies ahead.
2. **Virtual wall** (Sec. 3.2, :func:`object_ends`): from the outermost blocking beams walk
   outwards (up to +-beta) while successive returns are closer than d_max to each other;
   the last points are the object's ends; N_wall points are spread between them (k_RW).
3. **Side** (Sec. 3.3): one virtual obstacle (k_RD) at the end on the side *not* taken.
4. **Force** (eq. 4) = goal + obstacles + virtual wall + virtual obstacle; both virtual
   objects stay fixed in the world frame until
5. **Abandonment** (Sec. 3.4): the angle between F_w and F_goal is within delta_gamma.

Choices where the paper is silent or ambiguous are listed in docs/planners.md (sector
centred on the goal direction, the side rule, the virtual obstacle at the other end).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from nodes.planner.apf import APFParams, Repulsors, apf_force, coulomb_sum, wrap_angle
from nodes.planner.core import Plan, ScanView
from papf.errors import ConfigError

OBSTACLE_PLACES = ("beside", "end", "midpoint")


@dataclass(frozen=True)
class ARAPFParams:
    """AR-APF Table 1 parameters (charges as PAPF Table 1: q_R = q_O = q_W = q_D = -1, q_T = 1)."""

    k_ro_l: float = 5.0             # k_RO * L: Table 1 gives k_RO = 5 / L
    range_limited: bool = True      # repulsion only within APFParams.d_o (ours; eq. 2 has no range)
    k_virtual_factor: float = 10.0  # k_RW = k_RD = 10 k_RO (Table 1)
    alpha_deg: float = 30.0         # detection half-angle (Table 1)
    d_min: float = 1.2              # [m] detection distance (Table 1)
    s_min: float = 0.5              # [m] narrowest passage (Table 1)
    d_max: float = 0.2              # [m] gap between successive returns that ends an object
    n_wall: int = 10                # virtual wall points (Table 1)
    beta_deg: float = 75.0          # wall construction half-angle (Table 1)
    delta_gamma_deg: float = 5.0    # abandonment tolerance between F_w and F_goal (Table 1)
    wall_range_limited: bool = True  # virtual wall acts only within d_o like obstacles (ours)
    obstacle_at: str = "beside"     # virtual obstacle: beside | end | midpoint (ours, see docs)


def _sector_order(view: ScanView, centre: float, half_angle: float) -> tuple[np.ndarray, np.ndarray]:
    """Beam indices within +-half_angle of ``centre``, sorted right (CW) to left (CCW), and rel angles."""
    rel = np.array([wrap_angle(a - centre) for a in view.angles])
    idx = np.flatnonzero(np.abs(rel) <= half_angle)
    order = idx[np.argsort(rel[idx], kind="stable")]
    return order, rel


def _beam_point(view: ScanView, i: int, r: float | None = None) -> np.ndarray:
    r = view.ranges[i] if r is None else r
    return view.origin + r * np.array([math.cos(view.angles[i]), math.sin(view.angles[i])])


def detect_minimum(view: ScanView, goal: np.ndarray, ap: ARAPFParams):
    """Sec. 3.1: the sector's beam order (right to left) and its blocking mask, or None if free.

    A free run's width is the distance between the returns that bound it; a run reaching the
    sector's edge is bounded there by the point at d_min on the edge beam.
    """
    to_goal = goal - view.origin
    order, _ = _sector_order(view, math.atan2(to_goal[1], to_goal[0]), math.radians(ap.alpha_deg))
    if order.size == 0:
        return None
    ranges = view.ranges[order]
    blocked = ranges < ap.d_min
    if not blocked.any() or np.hypot(*to_goal) <= ranges[blocked].min():
        return None
    bounds = [_beam_point(view, order[0], ap.d_min) if not blocked[0] else None]
    run_start = None
    for k in range(order.size + 1):
        free = k < order.size and not blocked[k]
        if free and run_start is None:
            run_start = k
        elif not free and run_start is not None:
            right = _beam_point(view, order[run_start - 1]) if run_start > 0 else bounds[0]
            left = _beam_point(view, order[k]) if k < order.size else _beam_point(view, order[-1], ap.d_min)
            if np.hypot(*(left - right)) >= ap.s_min:
                return None
            run_start = None
    return order, blocked


def object_ends(view: ScanView, order: np.ndarray, blocked: np.ndarray, goal: np.ndarray,
                ap: ARAPFParams) -> tuple[np.ndarray, np.ndarray]:
    """Sec. 3.2: (right end, left end) of the object, walking out from the outer blocking beams."""
    to_goal = goal - view.origin
    centre = math.atan2(to_goal[1], to_goal[0])
    beta = math.radians(ap.beta_deg)
    n = view.ranges.size
    hits = order[blocked]
    ends = []
    for start, step in ((hits[0], -1), (hits[-1], +1)):
        i, p = start, _beam_point(view, start)
        for _ in range(n):
            j = (i + step) % n
            if not view.valid[j] or abs(wrap_angle(view.angles[j] - centre)) > beta:
                break
            q = _beam_point(view, j)
            if np.hypot(*(q - p)) > ap.d_max:
                break
            i, p = j, q
        ends.append(p)
    return ends[0], ends[1]


def virtual_obstacle(pos, goal, right, left, how: str = "beside") -> np.ndarray:
    """Sec. 3.3: side choice and the virtual obstacle's position (world frame).

    Side: around the end giving the shorter path robot -> end -> goal (ties: left; the
    paper draws at random). The obstacle goes on the other side: ``beside`` the robot,
    half the wall's length away perpendicular to the goal direction (default); at the
    other ``end``; or at the ``midpoint`` between the robot and the other end.
    """
    cost_r = np.hypot(*(right - pos)) + np.hypot(*(goal - right))
    cost_l = np.hypot(*(left - pos)) + np.hypot(*(goal - left))
    go_left = cost_l <= cost_r + 1e-3
    other = right if go_left else left
    if how == "end":
        return np.array(other, dtype=float)
    if how == "midpoint":
        return (pos + other) / 2.0
    u = (goal - pos) / np.hypot(*(goal - pos))
    n = np.array([u[1], -u[0]]) if go_left else np.array([-u[1], u[0]])   # right or left normal
    return pos + n * np.hypot(*(left - right)) / 2.0


class ARAPFStrategy:
    """AR-APF on the shared APF core (registered as ``arapf``)."""

    name = "arapf"
    Params = ARAPFParams

    def __init__(self, params: ARAPFParams | None = None):
        self.params = params or ARAPFParams()
        if self.params.obstacle_at not in OBSTACLE_PLACES:
            raise ConfigError(f"arapf obstacle_at={self.params.obstacle_at!r}: valid are "
                              f"{list(OBSTACLE_PLACES)}")
        self.reset()

    def reset(self) -> None:
        self.wall: np.ndarray | None = None       # (N_wall, 2) world frame
        self.obstacle: np.ndarray | None = None   # (1, 2) world frame

    def _field(self, apf: APFParams) -> APFParams:
        d_o = apf.d_o if self.params.range_limited else math.inf
        return dataclasses.replace(apf, k_vo_l=self.params.k_ro_l, d_o=d_o)

    def _augment(self, pos, goal, view: ScanView) -> None:
        ap = self.params
        found = detect_minimum(view, goal, ap)
        if found is None:
            return
        right, left = object_ends(view, *found, goal, ap)
        self.wall = np.linspace(right, left, ap.n_wall)
        self.obstacle = virtual_obstacle(pos, goal, right, left, ap.obstacle_at)[None, :]

    def plan(self, pos: np.ndarray, yaw: float, goal: np.ndarray, view: ScanView,
             apf: APFParams) -> Plan:
        ap, field = self.params, self._field(apf)
        fresh = self.wall is None
        if fresh:
            self._augment(pos, goal, view)
        force = apf_force(pos, goal, view.points, field, self._virtual(field))
        if self.wall is not None and not fresh:
            f_goal = -(field.k_vg * field.q_v * field.q_g) * coulomb_sum(pos, goal[None, :])
            cos = float(force @ f_goal) / max(np.linalg.norm(force) * np.linalg.norm(f_goal), 1e-300)
            if math.degrees(math.acos(max(-1.0, min(1.0, cos)))) <= ap.delta_gamma_deg:
                self.reset()                                   # Sec. 3.4: abandon AR
                force = apf_force(pos, goal, view.points, field)
        if self.wall is None:
            return Plan(force=force)
        return Plan(force=force, mode="augmented", virtual_walls=[self.wall],
                    virtual_obstacles=self.obstacle)

    def _virtual(self, field: APFParams) -> tuple[Repulsors, ...]:
        if self.wall is None:
            return ()
        k = self.params.k_virtual_factor * field.k_vo
        d_wall = field.d_o if self.params.wall_range_limited else math.inf
        return (Repulsors(self.wall, k, d_wall), Repulsors(self.obstacle, k))
