"""What the crowd-navigation planners (ORCA, social force) see around the robot. Pure.

Both plug-ins (``nodes/planner/orca``, ``nodes/planner/social_force``) take the same two
inputs the planner node has, and turn them into their libraries' terms here:

- **agents** from the obstacle tracks (``--objects truth`` or the tracker; a person is a
  disc, another robot its chassis box, taken as the disc around it): position, velocity,
  radius (:func:`agents`);
- **groups** among those agents (:func:`with_groups`): people whose discs are within
  ``group_gap_m`` of each other and who move alike (velocities within
  :data:`GROUP_SPEED_M_S`) are a group, and a group is one more agent, the disc around its
  members (centre: the members' centroid; radius: the farthest member's distance plus its
  radius; velocity: the members' mean) - nobody drives through a group (Kendon's o-space
  belongs to it; docs/planners.md "ORCA and social force");
- **static surroundings** from the scan (:func:`scan_segments`): the points within
  ``range_m`` that no track explains (farther than its radius + :data:`TRACK_MARGIN_M`),
  chained into polylines where consecutive beams' points are within ``SEGMENT_GAP_M`` - the
  walls and boxes the tracks do not cover - keeping a point only ``SEGMENT_MIN_M`` past the
  last one kept (a wall needs no vertex per beam; RVO2's obstacle tree costs per vertex).
"""

from __future__ import annotations

import math

import numpy as np

from common.robot import FOOTPRINT_RADIUS_M

TRACK_MARGIN_M = 0.15     # [m] scan points this close to a track's disc are that track's
SEGMENT_GAP_M = 0.3       # [m] consecutive scan points farther apart start a new polyline
SEGMENT_MIN_M = 0.15      # [m] a polyline's vertices at least this far apart (its ends kept)
GROUP_SPEED_M_S = 0.3     # [m/s] members of a group move alike: velocities this close
PERSON_MAX_RADIUS_M = 1.0  # [m] a track wider than this is no person (worlds/fleet.py's limit)
MOVING_M_S = 0.05         # [m/s] a track slower than this stands


def agents(tracks, pos: np.ndarray, reach_m: float) -> np.ndarray:
    """(k, 5) x, y, vx, vy, radius [m, m/s] of the tracks whose disc comes within
    ``reach_m`` of ``pos``: people, robots and whatever moves; a standing track wider than a
    person (a wall, a shelf: the ground truth lists them too) is left to the scan."""
    rows = []
    for tr in tracks:
        r = 0.5 * math.hypot(tr.length, tr.width) if tr.length != tr.width else 0.5 * tr.length
        if r <= 0 or (r > PERSON_MAX_RADIUS_M and math.hypot(tr.vx, tr.vy) < MOVING_M_S):
            continue
        if math.hypot(tr.x - pos[0], tr.y - pos[1]) - r <= reach_m:
            rows.append((tr.x, tr.y, tr.vx, tr.vy, r))
    return np.array(rows, float).reshape(-1, 5)


def with_groups(rows: np.ndarray, group_gap_m: float) -> np.ndarray:
    """``rows`` and, after them, one disc per group of people among them (module doc)."""
    n = len(rows)
    person = rows[:, 4] <= PERSON_MAX_RADIUS_M
    parent = list(range(n))

    def root(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for i in range(n):
        for j in range(i + 1, n):
            if not (person[i] and person[j]):
                continue
            gap = math.hypot(*(rows[i, :2] - rows[j, :2])) - rows[i, 4] - rows[j, 4]
            alike = math.hypot(*(rows[i, 2:4] - rows[j, 2:4])) <= GROUP_SPEED_M_S
            if gap <= group_gap_m and alike:
                parent[root(i)] = root(j)
    members: dict[int, list[int]] = {}
    for i in range(n):
        members.setdefault(root(i), []).append(i)
    extra = []
    for group in members.values():
        if len(group) < 2:
            continue
        g = rows[group]
        centre = g[:, :2].mean(axis=0)
        radius = float((np.hypot(*(g[:, :2] - centre).T) + g[:, 4]).max())
        extra.append((*centre, *g[:, 2:4].mean(axis=0), radius))
    return np.concatenate([rows, np.array(extra, float).reshape(-1, 5)])


def scan_segments(view, pos: np.ndarray, rows: np.ndarray, range_m: float) -> list[np.ndarray]:
    """Polylines ((k, 2) [m], k >= 2) of the scan points no track explains (module doc); a
    lone point becomes a segment of 2 cm across the beam, so it still counts."""
    pts = view.points
    if not len(pts):
        return []
    keep = np.hypot(*(pts - pos).T) <= range_m
    for x, y, _, _, r in rows:
        keep &= np.hypot(pts[:, 0] - x, pts[:, 1] - y) > r + TRACK_MARGIN_M
    lines: list[np.ndarray] = []
    chain: list[np.ndarray] = []
    for k in range(len(pts)):
        if keep[k] and chain and math.hypot(*(pts[k] - chain[-1])) <= SEGMENT_GAP_M:
            chain.append(pts[k])
            continue
        if chain:
            _polyline(lines, chain, view.origin)
        chain = [pts[k]] if keep[k] else []
    _polyline(lines, chain, view.origin)
    return lines


def _polyline(lines: list, chain: list, origin: np.ndarray) -> None:
    """A chain of consecutive points as a polyline: its ends, and the points between at least
    SEGMENT_MIN_M past the last kept; a single point as a 2 cm segment across its beam."""
    if len(chain) == 1:
        p = chain[0]
        d = p - origin
        n = np.array([-d[1], d[0]]) / max(math.hypot(*d), 1e-9) * 0.01
        lines.append(np.array([p - n, p + n], float))
    elif len(chain) > 1:
        verts = [chain[0]]
        for p in chain[1:-1]:
            if math.hypot(*(p - verts[-1])) >= SEGMENT_MIN_M:
                verts.append(p)
        verts.append(chain[-1])
        lines.append(np.array(verts, float))


def robot_radius(safety_m: float) -> float:
    """[m] the robot as the crowd planners see it: its circumscribed disc plus ``safety_m``."""
    return FOOTPRINT_RADIUS_M + safety_m


def to_unicycle(velocity: np.ndarray) -> tuple[float, float]:
    """A holonomic velocity [m/s] as (heading reference [rad], speed [m/s]) for the planner
    core's motion law (docs/planners.md "ORCA and social force": v = speed * cos(error),
    w from the shared heading controller)."""
    vx, vy = float(velocity[0]), float(velocity[1])
    return math.atan2(vy, vx), math.hypot(vx, vy)
