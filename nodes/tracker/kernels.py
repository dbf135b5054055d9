"""Clustering kernel of the tracker (step 2 of :mod:`nodes.tracker.core`) — numba when
available, the numpy version in :mod:`nodes.tracker.core` otherwise.

One pass over the scan's returns: breakpoints (the adaptive breakpoint detector), then
per segment the box of its points in their principal axes. The numba kernel does the
operations of the numpy path one return at a time (so results agree to rounding:
tests/unit/test_tracker.py compares them); it saves the ~40 numpy calls of the vectorised
version, which dominate a cycle on a scan of a few hundred returns.
"""

from __future__ import annotations

import math

import numpy as np

from common.optional import HAVE_NUMBA, numba_or_none

numba = numba_or_none()   # None without the extra "fast": the numpy twins run


def _segment_boxes(xy, ranges, beams, beam_count, increment, cluster_radius, lam, range_sd,
                   max_beam_gap):
    """(boxes (S, 5): x, y, axis, length, width; counts (S,); first) of the scan-order
    segments: segment s holds the returns ``(first + sum(counts[:s]) + q) % n``."""
    n = beams.shape[0]
    cut = np.zeros(n, dtype=np.bool_)
    last = -1
    for i in range(n):
        j = i + 1 if i + 1 < n else 0
        gap = (beams[j] - beams[i]) % beam_count
        if gap == 0:
            gap = beam_count
        dphi = gap * increment
        limit = 0.0
        if dphi < lam and gap <= max_beam_gap + 1:
            limit = max(cluster_radius,
                        ranges[i] * math.sin(dphi) / math.sin(lam - dphi) + 3 * range_sd)
        dx, dy = xy[j, 0] - xy[i, 0], xy[j, 1] - xy[i, 1]
        if dx * dx + dy * dy > limit * limit:
            cut[i] = True
            last = i
    first = 0 if last < 0 else (last + 1) % n
    boxes = np.empty((n, 5))
    counts = np.zeros(n, dtype=np.int64)
    s = 0
    k = 0
    while k < n:
        m = 1                                   # points in this segment, from order k
        while not cut[(first + k + m - 1) % n] and k + m < n:
            m += 1
        _box(xy, first, k, m, n, boxes[s])
        counts[s] = m
        s += 1
        k += m
    return boxes[:s], counts[:s], first


def _box(xy, first, k, m, n, out):
    mx = my = 0.0
    for q in range(m):
        p = (first + k + q) % n
        mx += xy[p, 0]
        my += xy[p, 1]
    mx /= m
    my /= m
    sxx = syy = sxy = 0.0
    for q in range(m):
        p = (first + k + q) % n
        dx, dy = xy[p, 0] - mx, xy[p, 1] - my
        sxx += dx * dx
        syy += dy * dy
        sxy += dx * dy
    axis = 0.5 * math.atan2(2 * sxy, sxx - syy)
    c, s = math.cos(axis), math.sin(axis)
    umin = vmin = math.inf
    umax = vmax = -math.inf
    for q in range(m):
        p = (first + k + q) % n
        dx, dy = xy[p, 0] - mx, xy[p, 1] - my
        u, v = dx * c + dy * s, dy * c - dx * s
        umin, umax = min(umin, u), max(umax, u)
        vmin, vmax = min(vmin, v), max(vmax, v)
    cu, cv = (umax + umin) / 2, (vmax + vmin) / 2
    out[0], out[1] = mx + c * cu - s * cv, my + s * cu + c * cv
    out[2], out[3], out[4] = axis, umax - umin, vmax - vmin


def _extents(points, c, s):
    """(min along, min across, max along, max across) [m] of ``points`` (m, 2) in the frame
    turned by (cos, sin) = (c, s): the box model's measurement (:func:`nodes.tracker.box.fit`)."""
    ulo = vlo = math.inf
    uhi = vhi = -math.inf
    for q in range(points.shape[0]):
        u = points[q, 0] * c + points[q, 1] * s
        v = points[q, 1] * c - points[q, 0] * s
        ulo, uhi = min(ulo, u), max(uhi, u)
        vlo, vhi = min(vlo, v), max(vhi, v)
    return ulo, vlo, uhi, vhi


if HAVE_NUMBA:
    _box = numba.njit(cache=True)(_box)
    segment_boxes = numba.njit(cache=True)(_segment_boxes)
    extents = numba.njit(cache=True)(_extents)
else:
    segment_boxes = extents = None
