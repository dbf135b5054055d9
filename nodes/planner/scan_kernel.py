"""Scan beams -> world-frame points (the non-trigonometric part of :func:`nodes.planner.core.scan_view`).

:func:`scan_points`: one compiled loop with numba, the numpy expressions it replaces
without; both bit for bit the same (tests/unit/test_papf_kernel.py). Used by the planner
core's scan view.
"""

from __future__ import annotations

import numpy as np

from nodes.planner.lazy import HAVE_NUMBA, numba_module


def _scan_points_numpy(ranges, cos_a, sin_a, range_min, range_max, finite_limits, origin):
    with np.errstate(invalid="ignore"):  # nan compares False; finite limits also drop +-inf
        valid = (ranges >= range_min) & (ranges <= range_max)
        if not finite_limits:
            valid &= np.isfinite(ranges)
    r = ranges[valid]
    points = origin + np.column_stack([r * cos_a[valid], r * sin_a[valid]])
    return np.where(valid, ranges, np.inf), points.reshape(-1, 2), valid


def _scan_points_loop(ranges, cos_a, sin_a, range_min, range_max, finite_limits,
                       origin):  # pragma: no cover - compiled
    """The compiled form's source (numba.njit of this, built by :func:`_compiled`)."""
    n = ranges.shape[0]
    out = np.empty(n)
    points = np.empty((n, 2))
    valid = np.empty(n, np.bool_)
    k = 0
    for i in range(n):
        r = ranges[i]
        ok = r >= range_min and r <= range_max and (finite_limits or np.isfinite(r))
        valid[i] = ok
        if ok:
            out[i] = r
            points[k, 0] = origin[0] + r * cos_a[i]
            points[k, 1] = origin[1] + r * sin_a[i]
            k += 1
        else:
            out[i] = np.inf
    return out, points[:k], valid


_COMPILED = []   # the numba dispatcher, once built


def _compiled():
    """The compiled loop, built at the first call that wants it: numba is imported only by
    a planner that runs compiled code (:mod:`nodes.planner.lazy`)."""
    if not _COMPILED:
        _COMPILED.append(numba_module().njit(cache=True, error_model="numpy")(_scan_points_loop))
    return _COMPILED[0]


def scan_points(ranges: np.ndarray, cos_a: np.ndarray, sin_a: np.ndarray, range_min: float,
                range_max: float, origin: np.ndarray, use_numba: bool = True):
    """``(ranges with inf where invalid, (K, 2) points of the valid beams, valid mask)``.

    A return is valid when finite and within [range_min, range_max]; ``ranges``, ``cos_a``,
    ``sin_a`` are float64 arrays of one length, ``origin`` the sensor position (2,).

    Each beam's range and the cosine and sine of its world-frame angle (numpy's own
    ``cos``/``sin``: their rounding is numpy's) -> the ranges with invalid returns as ``inf``,
    the points ``origin + r (cos, sin)`` of the valid beams in scan order, and the valid mask
    (a product and a sum per coordinate).
    """
    finite = bool(np.isfinite(range_min) and np.isfinite(range_max))
    if use_numba and HAVE_NUMBA:
        return _compiled()(ranges, cos_a, sin_a, float(range_min), float(range_max), finite, origin)
    return _scan_points_numpy(ranges, cos_a, sin_a, range_min, range_max, finite, origin)
