"""Plain 2-D geometry of a world's obstacles (numpy, no physics engine).

- :func:`signed_distance`: distance from points to the nearest obstacle footprint (< 0 inside);
- :func:`cast_rays`: exact first-hit distances of rays from a point (cylinders: circles;
  boxes — walls too — their four edges);
- :func:`segment_wall`: a zero-thickness wall between two points, as an :class:`Obstacle`.

Obstacles at their t = 0 pose (moving obstacles: :meth:`World.obstacles_at` first). The
pybullet scene of the same world (:mod:`worlds.bullet`) is what the stack's sim collides
with and the LiDAR node casts into; this module serves the offline tools and tests.
"""

from __future__ import annotations

import math

import numpy as np

from worlds import Obstacle, World


def signed_distance(world: World, pts: np.ndarray) -> np.ndarray:
    """Distance from each (x, y) point to the nearest obstacle footprint [m] (< 0 inside)."""
    pts = np.asarray(pts, dtype=float).reshape(-1, 2)
    best = np.full(pts.shape[0], np.inf)
    for ob in world.obstacles:
        rel = pts - np.asarray(ob.center[:2])
        if ob.shape == "box":
            c, s = math.cos(ob.yaw), math.sin(ob.yaw)
            q = np.abs(np.column_stack([c * rel[:, 0] + s * rel[:, 1], -s * rel[:, 0] + c * rel[:, 1]]))
            q = q - np.array(ob.size) / 2
            d = np.hypot(*np.maximum(q, 0.0).T) + np.minimum(q.max(axis=1), 0.0)
        else:
            d = np.hypot(rel[:, 0], rel[:, 1]) - ob.radius
        best = np.minimum(best, d)
    return best


def clearance(world: World, x: float, y: float) -> float:
    """Distance from the point (x, y) to the nearest obstacle surface [m] (inf if none)."""
    return float(signed_distance(world, np.array([x, y]))[0])


def cast_rays(world: World, x: float, y: float, angles: np.ndarray,
              range_max: float = math.inf) -> np.ndarray:
    """First-hit distance of a ray from (x, y) along each world-frame angle [m]; inf = none."""
    dx, dy = np.cos(angles), np.sin(angles)
    best = np.full(np.shape(angles), np.inf)
    for ob in world.obstacles:
        if ob.shape == "box":
            corners = ob.corners()
            for (x0, y0), (x1, y1) in zip(corners, corners[1:] + corners[:1], strict=True):
                best = _segment_hits(best, x, y, dx, dy, x0, y0, x1, y1)
            continue
        ox, oy = x - ob.center[0], y - ob.center[1]
        b = ox * dx + oy * dy
        disc = b * b - (ox * ox + oy * oy - ob.radius ** 2)
        with np.errstate(invalid="ignore"):
            t = -b - np.sqrt(disc)
        best = np.where((disc >= 0) & (t > 0) & (t < best), t, best)
    return np.where(best <= range_max, best, np.inf)


def _segment_hits(best, x, y, dx, dy, x0, y0, x1, y1):
    ex, ey = x1 - x0, y1 - y0
    den = dx * ey - dy * ex
    with np.errstate(divide="ignore", invalid="ignore"):
        t = ((x0 - x) * ey - (y0 - y) * ex) / den
        u = ((x0 - x) * dy - (y0 - y) * dx) / den
    ok = (np.abs(den) > 1e-12) & (t > 0) & (u >= 0) & (u <= 1) & (t < best)
    return np.where(ok, t, best)


def segment_wall(x0: float, y0: float, x1: float, y1: float) -> Obstacle:
    """A zero-thickness wall from (x0, y0) to (x1, y1) (a box of no width)."""
    return Obstacle("wall", "box", ((x0 + x1) / 2, (y0 + y1) / 2),
                    (math.hypot(x1 - x0, y1 - y0), 0.0), yaw=math.atan2(y1 - y0, x1 - x0))
