"""Plain 2-D geometry of a world's obstacles (numpy, no physics engine).

- :func:`signed_distance`: distance from points to the nearest obstacle footprint (< 0 inside);
- :func:`cast_rays`: exact first-hit distances of rays from a point (each obstacle kind's
  :meth:`~worlds.kinds.base.Kind.cast`);
- :func:`segment_wall`: a zero-thickness wall between two points, as an :class:`Obstacle`.

Obstacles at their t = 0 pose (moving obstacles: :meth:`World.obstacles_at` first). The
pybullet scene of the same world (:mod:`worlds.bullet`) is what the stack's sim collides
with and the LiDAR node casts into; this module serves the offline tools and tests.
"""

from __future__ import annotations

import math

import numpy as np

from worlds import World
from worlds.kinds.wall import segment_wall  # noqa: F401 (re-exported)


def signed_distance(world: World, pts: np.ndarray) -> np.ndarray:
    """Distance from each (x, y) point to the nearest obstacle footprint [m] (< 0 inside)."""
    pts = np.asarray(pts, dtype=float).reshape(-1, 2)
    best = np.full(pts.shape[0], np.inf)
    for ob in world.obstacles:
        best = np.minimum(best, ob.model.distance(ob, pts))
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
        best = ob.model.cast(ob, x, y, dx, dy, best, range_max)
    return np.where(best <= range_max, best, np.inf)
