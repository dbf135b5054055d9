"""The social-navigation measures' geometry, pure: Hall's zones, a group's space, time to
collision, who caused a collision, the people's path and time extension.

Sources (docs/experiments.md "Measures" names each beside its figure):

- **Hall's zones** (E. T. Hall 1966, *The Hidden Dimension*; the distances of Francis et al.
  2023, "Principles and guidelines for evaluating social robot navigation algorithms",
  and of HuNavSim's intimate/personal/social space intrusions, Pérez-Higueras et al. 2023):
  intimate 0.45 m, personal 1.2 m, social 3.6 m, measured here from the robot's footprint
  to the person's disc (the gap, as CrowdNav's discomfort distance is);
- **a group's space**: the convex hull of its members' centres grown by their mean radius
  (for two, the strip between them) - the space an F-formation holds between its members
  (Kendon 1990's o-space with the members' p-space; the "group space" of Rios-Martinez et
  al. 2015, "From proxemics theory to socially-aware navigation: a survey"). Driving into it
  is driving through the group. A group holds a space only while its members are together:
  no two of them farther apart than Hall's personal distance, :data:`TOGETHER_M` between
  their bodies (a walking pair split by a crowd is two people, and a robot between them
  crosses no group);
- **time to collision** (HuNavSim's and SocNavBench's): at constant velocities, the first
  time the robot's circumscribed disc (:data:`common.robot.FOOTPRINT_RADIUS_M`) touches a
  person's disc; 0 when they overlap while closing, inf when not closing;
- **who caused a collision** (HuNavSim's robot-on-person and person-on-robot collisions,
  which compare how straight and how fast each heads at the other): here the closing-speed
  components - the robot's velocity toward the person against the person's toward the
  robot; the larger one caused it (a tie: the robot);
- **the people's path and time extension** (Francis et al. 2023's "effect on people"; the
  path and time ratios SocNavBench and HuNavSim report for the agents): each reacting
  person's walk to its goal with the robot against the same scene, same seed, without it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from common.robot import FOOTPRINT_RADIUS_M

HALL_ZONES = (("intimate", 0.45), ("personal", 1.2), ("social", 3.6))   # [m] (module doc)
TOGETHER_M = 1.2   # [m] a group's members no farther apart than this (Hall's personal distance)


def _cross(o, a, b) -> float:
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])


def convex_hull(points: np.ndarray) -> np.ndarray:
    """(k, 2) the hull's vertices counter-clockwise (Andrew's monotone chain); 1 or 2 points
    (or all collinear) give the points' extreme ones."""
    pts = sorted(set(map(tuple, np.asarray(points, float).reshape(-1, 2).tolist())))
    if len(pts) <= 2:
        return np.array(pts, float).reshape(-1, 2)
    lower: list = []
    upper: list = []
    for p in pts:
        while len(lower) >= 2 and _cross(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    for p in reversed(pts):
        while len(upper) >= 2 and _cross(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    return np.array(lower[:-1] + upper[:-1], float)


def _point_segment(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(n,) [m] from each point (n, 2) to the segment a-b."""
    ab = b - a
    L2 = float(ab @ ab)
    t = np.zeros(len(p)) if L2 == 0 else np.clip(((p - a) @ ab) / L2, 0.0, 1.0)
    return np.hypot(*(a + t[:, None] * ab - p).T)


def _axes(poly: np.ndarray) -> list:
    """Edge normals of a polygon (a segment's one normal; a point's none)."""
    if len(poly) < 2:
        return []
    edges = np.roll(poly, -1, axis=0) - poly if len(poly) > 2 else poly[1:] - poly[:1]
    return [np.array([-e[1], e[0]]) / math.hypot(*e) for e in edges if math.hypot(*e) > 0]


def polygon_gap(a: np.ndarray, b: np.ndarray) -> float:
    """[m] between two convex polygons (vertices (k, 2); a segment or a point is one too);
    0 when they touch or overlap."""
    for axis in _axes(a) + _axes(b):
        pa, pb = a @ axis, b @ axis
        if pa.max() < pb.min() or pb.max() < pa.min():
            return _vertex_edge_min(a, b)
    return 0.0 if len(a) > 1 or len(b) > 1 else float(math.hypot(*(a[0] - b[0])))


def _vertex_edge_min(a: np.ndarray, b: np.ndarray) -> float:
    """The least distance of a vertex of one polygon to an edge (or vertex) of the other."""
    best = math.inf
    for p, q in ((a, b), (b, a)):
        ends = range(len(q)) if len(q) > 2 else range(max(len(q) - 1, 1))
        for k in ends:
            s, e = q[k], q[(k + 1) % len(q)]
            best = min(best, float(_point_segment(p, s, e).min()))
    return best


def together(centres: np.ndarray, radii: np.ndarray) -> bool:
    """No two members' bodies farther apart than :data:`TOGETHER_M` (module doc)."""
    c = np.asarray(centres, float).reshape(-1, 2)
    r = np.asarray(radii, float).reshape(-1)
    gaps = np.hypot(*(c[:, None, :] - c[None, :, :]).transpose(2, 0, 1)) - r[:, None] - r[None, :]
    return bool(gaps.max() <= TOGETHER_M) if len(c) > 1 else True


def group_gap(footprint: np.ndarray, centres: np.ndarray, radius: float) -> float:
    """[m] from the robot's footprint (its (4, 2) corners) to a group's space (module doc)
    of members at ``centres`` (k, 2) [m]; <= 0: inside it."""
    return polygon_gap(footprint, convex_hull(centres)) - radius


def time_to_collision(robot_xy, robot_v, people_xy: np.ndarray, people_v: np.ndarray,
                      radii: np.ndarray, robot_radius: float = FOOTPRINT_RADIUS_M) -> float:
    """[s] the least time until the robot's disc touches a person's at constant velocities
    (module doc); inf when nobody closes in."""
    d = np.asarray(people_xy, float).reshape(-1, 2) - np.asarray(robot_xy, float)
    u = np.asarray(people_v, float).reshape(-1, 2) - np.asarray(robot_v, float)
    reach = np.asarray(radii, float).reshape(-1) + robot_radius
    a = (u * u).sum(axis=1)
    b = (d * u).sum(axis=1)                 # < 0: closing
    c = (d * d).sum(axis=1) - reach ** 2
    closing = b < 0
    inside = closing & (c <= 0)
    disc = b * b - a * c
    hit = closing & ~inside & (disc >= 0) & (a > 0)
    t = np.full(len(d), math.inf)
    t[inside] = 0.0
    t[hit] = (-b[hit] - np.sqrt(disc[hit])) / a[hit]
    return float(t.min()) if len(t) else math.inf


def collision_cause(robot_xy, robot_v, person_xy, person_v) -> str:
    """``robot`` or ``person``: whose closing speed toward the other was the larger at the
    contact (module doc)."""
    d = np.asarray(person_xy, float) - np.asarray(robot_xy, float)
    n = float(math.hypot(*d))
    if n < 1e-9:
        return "robot"
    unit = d / n
    robot_in = float(np.asarray(robot_v, float) @ unit)
    person_in = float(-(np.asarray(person_v, float) @ unit))
    return "robot" if robot_in >= person_in else "person"


@dataclass(frozen=True)
class Extension:
    """The reacting people's walk with the robot against without it (module doc)."""

    people: int              # people who reached their goal in both runs (those compared)
    held: int                # people who reached it without the robot but not with it
    path_m: float            # mean extra path to the goal [m] (nan: nobody compared)
    time_s: float            # mean extra time to the goal [s]
    path_pct: float          # mean extra path [% of the path without the robot]
    time_pct: float          # mean extra time [%]


def extension(with_t: np.ndarray, with_path: np.ndarray, without_t: np.ndarray,
              without_path: np.ndarray) -> Extension:
    """Per person: the time [s] it reached its goal and the path [m] it had walked then, in
    the run with the robot and in the run without (nan: not reached) -> the means."""
    wt, wp = np.asarray(with_t, float), np.asarray(with_path, float)
    ot, op = np.asarray(without_t, float), np.asarray(without_path, float)
    both = ~np.isnan(wt) & ~np.isnan(ot)
    held = int((np.isnan(wt) & ~np.isnan(ot)).sum())
    if not both.any():
        return Extension(0, held, math.nan, math.nan, math.nan, math.nan)
    dp, dt = wp[both] - op[both], wt[both] - ot[both]
    pct = lambda d, base: float(np.mean(100.0 * d / np.maximum(base, 1e-9)))  # noqa: E731
    return Extension(int(both.sum()), held, float(dp.mean()), float(dt.mean()),
                     pct(dp, op[both]), pct(dt, ot[both]))
