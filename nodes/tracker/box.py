"""The tracker's box model: a cluster measured as its track's box (pure maths, no state).

A LiDAR sees only the faces of a car turned towards it, so a matched cluster is measured
in its track's frame as the centre of a box of the track's size whose nearest faces lie
on the seen points (:func:`fit`); a new heading only re-labels the sides (:func:`turned`).
A person or a cylinder is no box: its arc is measured as a circle (:func:`disc`).
Used by :class:`nodes.tracker.core.Tracker`.
"""

from __future__ import annotations

import math

import numpy as np

from nodes.tracker import kernels

DISC_MIN_POINTS = 5    # [-] fewer points fit a circle and a corner alike
DISC_MARGIN = 1.5      # [-] a disc's circle fits this many times better than a line or corner


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


def disc(points: np.ndarray, origin: tuple[float, float], max_radius: float,
         max_rms: float) -> tuple[float, float, float] | None:
    """``(x, y, radius)`` [m] of the circle ``points`` (m, 2, in scan order) lie on when they
    are the visible arc of a disc (a person, a cylinder) seen from ``origin``, else None.

    Kåsa's algebraic fit (I. Kåsa, IEEE Trans. Instrum. Meas. 25, 1976: least squares of
    ``x² + y² = a x + b y + c``, on points centred for conditioning, in closed form). An arc
    when: at least :data:`DISC_MIN_POINTS` points, radius <= ``max_radius``, RMS distance to
    the circle <= ``max_rms`` and :data:`DISC_MARGIN` times below the RMS of a line and of a
    corner (two lines split at the point farthest from the chord: what a box shows), the
    arc spanning at least 60 deg (chord >= radius), its centre beyond the points seen from
    the sensor. On the road worlds' cars ``papf bench tracker`` gives the same accuracy
    with it as without it.

    Why: the box model measures a disc as a box of the extents seen, half a disc deep, so a
    person's track sits about half a radius short of its centre (0.15 m for a 0.3 m person)
    and is half as deep as it is.
    """
    n = len(points)
    if n < DISC_MIN_POINTS:
        return None
    mid = points.mean(axis=0)
    d = points - mid
    u, v = d[:, 0], d[:, 1]
    q = u * u + v * v
    # the normal equations of the centred fit (sum u = sum v = 0): a 2x2 system and c
    suu, svv, suv = float(u @ u), float(v @ v), float(u @ v)
    det = suu * svv - suv * suv
    if det <= 1e-18:
        return None                                     # collinear points: a face
    bu, bv = float(u @ q), float(v @ q)
    cx = 0.5 * (svv * bu - suv * bv) / det
    cy = 0.5 * (suu * bv - suv * bu) / det
    r2 = float(q.mean()) + cx * cx + cy * cy
    if not 0 < r2 <= max_radius * max_radius:
        return None
    r = math.sqrt(r2)
    x, y = float(mid[0] + cx), float(mid[1] + cy)
    if math.hypot(x - origin[0], y - origin[1]) <= math.hypot(mid[0] - origin[0], mid[1] - origin[1]):
        return None
    if math.hypot(*(points[0] - points[-1]).tolist()) < r:
        return None
    res = np.sqrt((u - cx) ** 2 + (v - cy) ** 2) - r
    rms = math.sqrt(float(res @ res) / n)
    if rms > max_rms or DISC_MARGIN * rms >= min(_line_rms(points), _corner_rms(points)):
        return None
    return x, y, r


def disc_seen(points: np.ndarray, origin: tuple[float, float], radius: float) -> tuple[float, float]:
    """Centre [m] of a disc of ``radius`` [m] whose nearest seen point is ``points``' nearest
    to ``origin``, on the bearing of their mean: a disc track's cluster that is no clean arc."""
    rel = points - np.asarray(origin)
    near = float(np.sqrt((rel * rel).sum(axis=1)).min())
    m = rel.mean(axis=0)
    u = m / max(float(np.hypot(*m)), 1e-12)
    return float(origin[0] + (near + radius) * u[0]), float(origin[1] + (near + radius) * u[1])


def _line_ss(points: np.ndarray) -> float:
    """Sum of squared distances [m²] of ``points`` to their total-least-squares line."""
    if len(points) < 3:
        return 0.0
    d = points - points.mean(axis=0)
    sxx, syy, sxy = float(d[:, 0] @ d[:, 0]), float(d[:, 1] @ d[:, 1]), float(d[:, 0] @ d[:, 1])
    return max(0.0, 0.5 * (sxx + syy) - math.hypot(0.5 * (sxx - syy), sxy))   # least eigenvalue


def _line_rms(points: np.ndarray) -> float:
    """RMS distance [m] of ``points`` to their line."""
    return math.sqrt(_line_ss(points) / len(points))


def _corner_rms(points: np.ndarray) -> float:
    """RMS distance [m] of ``points`` to two lines meeting at the point farthest from the
    chord (first to last point): a box's corner."""
    a, b = points[0], points[-1]
    u = (b - a) / max(float(np.hypot(*(b - a))), 1e-12)
    off = np.abs((points[:, 0] - a[0]) * u[1] - (points[:, 1] - a[1]) * u[0])
    k = min(max(int(np.argmax(off)), 1), len(points) - 2)
    return math.sqrt((_line_ss(points[:k + 1]) + _line_ss(points[k:])) / len(points))
