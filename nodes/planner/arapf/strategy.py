"""AR-APF as a planner strategy (Szczepanski, Energies 2021, 14, 6642).

On a local minimum ahead (Sec. 3.1) a virtual wall across the object and a virtual obstacle
beside the robot (Secs. 3.2-3.3, eq. 4) push it round until abandonment (Sec. 3.4); without
one it is APF with ``k_vo_l = 5``. Registered as ``arapf`` (planar scans only). The steps:
docs/planners.md, "The algorithms in the code"; the choices: its AR-APF section.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from common.errors import ConfigError
from nodes.planner.arapf.settings import AR_REPULSION_MIN, ARAPF
from nodes.planner.core import Plan, ScanView, Strategy
from nodes.planner.debug import DebugField, Style
from nodes.planner.field import APFParams, Repulsors, apf_force, coulomb_sum, wrap_angle
from nodes.planner.settings import require_product

PASSAGE_WIDTHS = ("opening", "gap")


@dataclass(frozen=True)
class ARAPFParams:
    """AR-APF Table 1 parameters (q_R = q_O = q_W = q_D = -1, q_T = 1) and our choices."""

    k_ro_l: float = 5.0             # k_RO * L: Table 1 gives k_RO = 5 / L
    k_virtual_factor: float = 10.0  # k_RW = k_RD = 10 k_RO (Table 1)
    alpha_deg: float = 30.0         # detection half-angle (Table 1)
    d_min: float = 1.2              # [m] detection distance (Table 1)
    s_min: float = 0.5              # [m] narrowest passage (Table 1)
    d_max: float = 0.2              # [m] gap between successive returns that ends an object (Table 1)
    n_wall: int = 10                # virtual wall points (Table 1)
    beta_deg: float = 75.0          # wall construction half-angle (Table 1)
    delta_gamma_deg: float = 5.0    # abandonment tolerance between F_w and F_goal (Table 1)
    range_limited: bool = True      # obstacles repel only within APFParams.d_o (ours; eq. 2 has no range)
    wall_range_limited: bool = True  # wall points too, like perceived points (ours)
    obstacle_offset_m: float = 0.25  # [m] virtual obstacle beside the robot (ours: s_min / 2)
    follow: bool = True             # re-place the obstacle while the wall still closes the way (ours)
    passage_width: str = "opening"  # opening (chord at the nearer bound) | gap (bound to bound) (ours)


# -- Sec. 3.1: detection -----------------------------------------------------------------
def opening(r_a: float, r_b: float, dtheta: float) -> float:
    """Width [m] of a free run between bounds at ranges r_a, r_b, dtheta [rad] apart.

    The chord at the nearer bound, 2 min(r) sin(dtheta / 2): the opening the robot would
    have to pass through next to the nearer obstacle.
    """
    return 2.0 * min(r_a, r_b) * math.sin(abs(dtheta) / 2.0)


def _gap(r_a: float, a: float, r_b: float, b: float) -> float:
    """Straight distance between the two bounding points (the ``gap`` reading)."""
    return math.hypot(r_b * math.cos(b) - r_a * math.cos(a), r_b * math.sin(b) - r_a * math.sin(a))


def detect_minimum(view: ScanView, goal: np.ndarray, ap: ARAPFParams):
    """Sec. 3.1: (sector beam indices right to left, blocked mask) if a minimum lies ahead, else None.

    The sector is +-alpha about the direction from the sensor to the goal. A free run
    reaching the sector's edge is bounded there by the edge ray at d_min. A goal nearer
    than the nearest blocking return is not behind a minimum.
    """
    to_goal = goal - view.origin
    centre, half = math.atan2(to_goal[1], to_goal[0]), math.radians(ap.alpha_deg)
    rel = (view.angles - centre + math.pi) % (2.0 * math.pi) - math.pi
    idx = np.flatnonzero(np.abs(rel) <= half)
    if idx.size == 0:
        return None
    order = idx[np.argsort(rel[idx], kind="stable")]
    ranges, angles = view.ranges[order], rel[order]
    blocked = ranges < ap.d_min
    if not blocked.any() or np.hypot(*to_goal) <= ranges[blocked].min():
        return None
    edges = np.flatnonzero(np.diff(np.concatenate(([True], blocked, [True])).astype(int)))
    for start, stop in zip(edges[::2], edges[1::2], strict=True):   # free runs [start, stop)
        r_a, a = (ranges[start - 1], angles[start - 1]) if start > 0 else (ap.d_min, -half)
        r_b, b = (ranges[stop], angles[stop]) if stop < order.size else (ap.d_min, half)
        width = opening(r_a, r_b, b - a) if ap.passage_width == "opening" else _gap(r_a, a, r_b, b)
        if width >= ap.s_min:
            return None
    return order, blocked


# -- Sec. 3.2: virtual wall --------------------------------------------------------------
def _beam_point(view: ScanView, i: int) -> np.ndarray:
    return view.origin + view.ranges[i] * np.array([math.cos(view.angles[i]), math.sin(view.angles[i])])


def object_ends(view: ScanView, order: np.ndarray, blocked: np.ndarray, goal: np.ndarray,
                ap: ARAPFParams) -> tuple[np.ndarray, np.ndarray]:
    """Sec. 3.2: (right end, left end), walking out beam by beam from the outer blocking beams.

    The walk goes on while the next return is valid, within +-beta of the goal direction
    and no more than d_max from the previous one; the last point reached is the end.
    """
    to_goal = goal - view.origin
    centre, beta = math.atan2(to_goal[1], to_goal[0]), math.radians(ap.beta_deg)
    n, hits, ends = view.ranges.size, order[blocked], []
    for start, step in ((hits[0], -1), (hits[-1], +1)):
        i, p = int(start), _beam_point(view, int(start))
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


def wall_points(right: np.ndarray, left: np.ndarray, n_wall: int) -> np.ndarray:
    """N_wall points equally spaced from the right end to the left end, both included."""
    return np.linspace(right, left, n_wall)


def with_wall(view: ScanView, a: np.ndarray, b: np.ndarray) -> tuple[ScanView, np.ndarray]:
    """The robot's augmented perception: the scan with segment a-b as an obstacle.

    Returns the view whose beams that cross the segment before their own return report
    the segment, and the mask of those beams.
    """
    d = np.column_stack([np.cos(view.angles), np.sin(view.angles)])
    e, w = b - a, a - view.origin
    den = d[:, 1] * e[0] - d[:, 0] * e[1]                       # ray o + t d = a + s e
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (w[1] * e[0] - w[0] * e[1]) / den
        s = (d[:, 0] * w[1] - d[:, 1] * w[0]) / den
    virtual = (np.abs(den) > 1e-12) & (t > 0.0) & (s >= 0.0) & (s <= 1.0) & (t < view.ranges)
    ranges = np.where(virtual, t, view.ranges)
    valid = view.valid | virtual
    points = view.origin + ranges[valid, None] * d[valid]
    return ScanView(view.origin, view.angles, ranges, points, valid), virtual


# -- Sec. 3.3: side and virtual obstacle -------------------------------------------------
def choose_left(pos, goal, right, left) -> bool:
    """Go round the left end? The shorter path robot -> end -> goal wins; ties go left.

    (The paper draws ties at random; we stay deterministic.)
    """
    cost_r = np.hypot(*(right - pos)) + np.hypot(*(goal - right))
    cost_l = np.hypot(*(left - pos)) + np.hypot(*(goal - left))
    return bool(cost_l <= cost_r + 1e-9)


def obstacle_beside(pos, goal, go_left: bool, offset: float) -> np.ndarray:
    """The virtual obstacle on the robot's side not taken, ``offset`` across the goal direction."""
    u = (goal - pos) / np.hypot(*(goal - pos))
    right_normal = np.array([u[1], -u[0]])
    return pos + (right_normal if go_left else -right_normal) * offset


# -- Sec. 3.4: abandonment ---------------------------------------------------------------
def angle_deg(a: np.ndarray, b: np.ndarray) -> float:
    """Angle between two vectors [deg] (180 if either is zero)."""
    na, nb = float(np.linalg.norm(a)), float(np.linalg.norm(b))
    if na == 0.0 or nb == 0.0:
        return 180.0
    return math.degrees(math.acos(max(-1.0, min(1.0, float(a @ b) / (na * nb)))))


def abandon(force: np.ndarray, f_goal: np.ndarray, delta_gamma_deg: float) -> bool:
    """Sec. 3.4: F_w and F_goal point the same way within delta_gamma."""
    return angle_deg(force, f_goal) <= delta_gamma_deg


class ARAPFStrategy(Strategy):
    """AR-APF on the shared APF core (registered as ``arapf``)."""

    name = "arapf"
    rank = 2
    roles = ("compared", "traffic", "crowd", "arapf-proposed")
    colour, colour_map = "tab:purple", "Purples"
    planar_only = True   # reads the scan's beams (local minimum, object ends), not just points
    Params = ARAPFParams
    SPECS = ARAPF
    #: ``--preset paper``: eqs. 2-4 without range limits, the obstacle placed once, the
    #: passage measured bound to bound (docs/planners.md, "Presets").
    PAPER_PRESET = {"range_limited": False, "wall_range_limited": False, "follow": False,
                    "passage_width": "gap"}
    DEBUG = (
        DebugField("virtual_walls", "paths", unit="m", label="virtual wall",
                   doc="the virtual wall's points across the passage (eq. 3, k_RW)",
                   style=Style((0.89, 0.47, 0.76, 1.0), 0.05)),
        DebugField("virtual_obstacles", "points", unit="m", label="virtual obstacle",
                   doc="the virtual obstacle beside the goal line (eq. 4, k_RD)",
                   style=Style((0.89, 0.47, 0.76, 0.9), 0.1)),
    )


    @classmethod
    def check_strength(cls, apf, params) -> None:
        """The virtual obstacles' repulsion ``k_ro_l*q_v*q_o`` above its measured floor."""
        require_product("k_ro_l*q_v*q_o", params.k_ro_l * apf.q_v * apf.q_o, AR_REPULSION_MIN)

    def __init__(self, params: ARAPFParams | None = None):
        self.params = params or ARAPFParams()
        if self.params.passage_width not in PASSAGE_WIDTHS:
            raise ConfigError(f"arapf passage_width={self.params.passage_width!r}: valid are "
                              f"{list(PASSAGE_WIDTHS)}")
        if not 2 <= self.params.n_wall:
            raise ConfigError(f"arapf n_wall={self.params.n_wall!r}: must be an integer >= 2")
        self.reset()

    def reset(self) -> None:
        """Drop the augmented reality (new goal, or abandonment)."""
        self.wall: np.ndarray | None = None       # (N_wall, 2) world frame
        self.obstacle: np.ndarray | None = None   # (1, 2) world frame
        self.go_left = True

    def _field(self, apf: APFParams) -> APFParams:
        d_o = apf.d_o if self.params.range_limited else math.inf
        return dataclasses.replace(apf, k_vo_l=self.params.k_ro_l, d_o=d_o)

    def _augment(self, pos, goal, view: ScanView) -> bool:
        """Without AR: detect, build wall, side and obstacle. True if AR was created."""
        ap = self.params
        found = detect_minimum(view, goal, ap)
        if found is None:
            return False
        right, left = object_ends(view, *found, goal, ap)
        self.wall = wall_points(right, left, ap.n_wall)
        self.go_left = choose_left(pos, goal, right, left)
        self.obstacle = obstacle_beside(pos, goal, self.go_left, ap.obstacle_offset_m)[None, :]
        return True

    def _follow(self, pos, goal, view: ScanView) -> None:
        """With AR: while the perceived wall still closes the way ahead, keep the obstacle beside."""
        seen, virtual = with_wall(view, self.wall[0], self.wall[-1])
        found = detect_minimum(seen, goal, self.params)
        if found is not None and virtual[found[0][found[1]]].any():
            self.obstacle = obstacle_beside(pos, goal, self.go_left, self.params.obstacle_offset_m)[None, :]

    def plan(self, pos: np.ndarray, yaw: float, goal: np.ndarray, view: ScanView,
             apf: APFParams) -> Plan:
        """Eq. 4 at ``pos`` [m]: goal, obstacles, and the virtual wall and obstacle while a local minimum is handled."""
        ap, field = self.params, self._field(apf)
        if self.wall is None:
            fresh = self._augment(pos, goal, view)
        else:
            fresh = False
            if ap.follow:
                self._follow(pos, goal, view)
        force = apf_force(pos, goal, view.points, field, self._virtual(field))
        if self.wall is not None and not fresh:
            f_goal = -(field.k_vg * field.q_v * field.q_g) * coulomb_sum(pos, goal[None, :])
            if abandon(force, f_goal, ap.delta_gamma_deg):
                self.reset()
                force = apf_force(pos, goal, view.points, field)
        if self.wall is None:
            return Plan(force=force)
        return Plan(force=force, mode="augmented",
                    debug={"virtual_walls": [self.wall], "virtual_obstacles": self.obstacle})

    def _virtual(self, field: APFParams) -> tuple[Repulsors, ...]:
        """Eq. 3-4 terms: wall points (k_RW, within d_o by default) and the obstacle (k_RD, no range)."""
        if self.wall is None:
            return ()
        k = self.params.k_virtual_factor * field.k_vo
        d_wall = field.d_o if self.params.wall_range_limited else math.inf
        return (Repulsors(self.wall, k, d_wall), Repulsors(self.obstacle, k))
