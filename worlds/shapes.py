"""Plain geometry of shapes that simulators and pictures share (numpy, no physics engine).

- :func:`rect_corners`: a rectangle along a heading (a car's or an obstacle's footprint) —
  the road runs (:mod:`papf.offline.car`) and the IAPF case figures;
- :func:`spheres_of`, :func:`sphere_clearance`: the sphere obstacles of a 3-D world and a
  point's distance to them — the 3-D point robot (:mod:`papf.offline.point3d`) and the
  3-D figures (:mod:`papf.plots.world3d`).
"""

from __future__ import annotations

import math

import numpy as np

from common.errors import ConfigError
from worlds import World


def rect_corners(x: float, y: float, yaw: float, length: float, width: float) -> np.ndarray:
    """(4, 2) corners of a rectangle centred at (x, y) along ``yaw`` [m], counter-clockwise."""
    c, s = math.cos(yaw), math.sin(yaw)
    hx, hy = 0.5 * length, 0.5 * width
    local = np.array([(-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy)])
    return np.column_stack([x + c * local[:, 0] - s * local[:, 1],
                            y + s * local[:, 0] + c * local[:, 1]])


def spheres_of(world: World) -> np.ndarray:
    """(K, 4) rows (cx, cy, cz, radius) of the world's sphere obstacles; ConfigError otherwise."""
    rows = []
    for i, ob in enumerate(world.obstacles):
        if 3 not in ob.model.world_dims:
            raise ConfigError(f"world {world.name!r}: obstacles[{i}] is a {ob.kind}; 3-D worlds "
                              "take only kind = \"sphere\" obstacles")
        rows.append((*ob.center[:3], ob.radius))
    return np.array(rows, dtype=float).reshape(-1, 4)


def sphere_clearance(pos: np.ndarray, spheres: np.ndarray) -> float:
    """Distance from the point to the nearest sphere surface [m] (< 0 inside); inf if none."""
    if spheres.shape[0] == 0:
        return math.inf
    return float(np.min(np.linalg.norm(spheres[:, :3] - pos, axis=1) - spheres[:, 3]))
