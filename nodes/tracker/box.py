"""The tracker's box model: a cluster measured as its track's box (pure maths, no state).

A LiDAR sees only the faces of a car turned towards it, so a matched cluster is measured
in its track's frame as the centre of a box of the track's size whose nearest faces lie
on the seen points (:func:`fit`); a new heading only re-labels the sides (:func:`turned`).
Used by :class:`nodes.tracker.core.Tracker`.
"""

from __future__ import annotations

import math

import numpy as np

from nodes.tracker import kernels


def anchor(lo: float, hi: float, size: float, sensor: float) -> float:
    """Centre of an extent ``size`` [m] long that holds the seen ``[lo, hi]`` with its face
    nearest ``sensor`` on the seen one. The seen extent's middle when it is the whole, or
    when the sensor faces it (then both ends are in view; it is shorter than ``size`` only
    by the spacing of the beams)."""
    if hi - lo >= size or lo <= sensor <= hi:
        return 0.5 * (lo + hi)
    return lo + 0.5 * size if sensor < 0.5 * (lo + hi) else hi - 0.5 * size


def fit(points: np.ndarray, yaw: float, size: tuple[float, float],
        origin: tuple[float, float], compiled: bool = True) -> tuple[float, float, float, float]:
    """``(x, y, along, across)``: the box centre [m] (world frame) of ``points`` (m, 2) for a
    box of ``size`` = (length along ``yaw``, width across) [m] seen from the sensor at
    ``origin``, and the points' own extents along / across ``yaw`` [m]. ``compiled``: the
    extents from the numba kernel when numba is installed (else numpy).

    Why: the centre of the visible points' box lies up to half a car off the car's centre,
    and it moves as the robot drives past and new faces come into view — a velocity the car
    does not have. The box's size is the largest extents seen so far (a rigid box keeps it).
    """
    c, s = math.cos(yaw), math.sin(yaw)
    if compiled and kernels.extents is not None:
        ulo, vlo, uhi, vhi = kernels.extents(points, c, s)
    else:
        uv = points @ np.array(((c, -s), (s, c)))        # columns: along, across
        (ulo, vlo), (uhi, vhi) = uv.min(axis=0).tolist(), uv.max(axis=0).tolist()
    mu = anchor(ulo, uhi, size[0], origin[0] * c + origin[1] * s)
    mv = anchor(vlo, vhi, size[1], origin[1] * c - origin[0] * s)
    return mu * c - mv * s, mu * s + mv * c, uhi - ulo, vhi - vlo


def turned(size: tuple[float, float], turn: float) -> tuple[float, float]:
    """A rigid box's (length, width) in a frame turned by ``turn`` [rad]: swapped when the
    turn is nearer a quarter turn than none (a new heading re-labels the box's sides; a
    projection of the box would inflate it with every small turn)."""
    return (size[1], size[0]) if abs(math.sin(turn)) > abs(math.cos(turn)) else size
