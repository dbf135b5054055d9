"""One PAPF cycle in two numba calls, bit for bit the numpy steps of :mod:`nodes.planner.papf.strategy`.

:meth:`~nodes.planner.papf.strategy.PAPFStrategy.plan` uses it when numba is installed (2-D,
prediction stopping at the goal); tests/unit/test_papf_kernel.py checks the identity. How
the cycle splits between kernels and numpy: docs/planners.md, "The algorithms in the code".
"""

from __future__ import annotations

import math

import numpy as np

from nodes.planner.field import EPS_M
from nodes.planner.papf.kernels import HAVE_NUMBA, numba
from nodes.planner.papf.params import kernel_params

if HAVE_NUMBA:
    from nodes.planner.papf.kernels import _field_numba, _predict_numba

    _jit = numba.njit(cache=True, error_model="numpy")

    @_jit
    def _front(start, goal, obstacles, quarks, kp):  # pragma: no cover - compiled
        """The prediction, eq. 2 at the robot and the distance of each quark in use."""
        paths, n_paths, length, qbuf, lo, hi, resolved, reached = _predict_numba(
            start, goal, obstacles, quarks, kp)
        f_apf = _field_numba(start, goal, obstacles, kp)
        qdist = np.empty(hi - lo)
        for k in range(hi - lo):
            rx, ry = qbuf[lo + k, 0] - start[0], qbuf[lo + k, 1] - start[1]
            qdist[k] = math.sqrt(rx * rx + ry * ry)
        return paths, n_paths, length, qbuf, lo, hi, resolved, reached, f_apf, qdist

    @_jit
    def _back(pos, pts, proj, u, eq8, target, obstacles, quarks, qdist, cube,
              kp):  # pragma: no cover - compiled
        """Eq. 8's point (when ``eq8``; else ``target`` stays) and the motion force at ``pos``.

        ``proj`` = ``(pts - pos) @ u`` and ``cube`` = the quarks' softened distance cubed,
        both from numpy; ``qdist`` from :func:`_front`.
        """
        if eq8:
            n = pts.shape[0]
            dist = np.empty(n)
            top = -np.inf
            for k in range(n):
                nx = (pts[k, 0] - pos[0]) - proj[k] * u[0]
                ny = (pts[k, 1] - pos[1]) - proj[k] * u[1]
                dist[k] = math.sqrt(nx * nx + ny * ny)
                if dist[k] > top or dist[k] != dist[k]:
                    top = dist[k]
            best = -1
            for k in range(n):
                if dist[k] >= top - kp.tie_tol:
                    best = k
            target = pts[best].copy()
        f = _field_numba(pos, target, obstacles, kp)
        if quarks.shape[0]:
            sx = sy = 0.0
            for k in range(quarks.shape[0]):
                if qdist[k] > EPS_M and qdist[k] <= kp.q_lim:
                    sx = sx + (quarks[k, 0] - pos[0]) / cube[k]
                    sy = sy + (quarks[k, 1] - pos[1]) / cube[k]
            f[0] = f[0] + (0.0 - kp.g_q * sx)
            f[1] = f[1] + (0.0 - kp.g_q * sy)
        else:
            f[0] = f[0] + 0.0
            f[1] = f[1] + 0.0
        return target, f


def plan_compiled(pos, goal, obstacles, apf, pp, quarks=None):
    """One PAPF cycle (2-D, ``pp.stop_at_goal``, numba): ``(path, quarks, abandoned,
    resolved, target, force)`` — what :func:`nodes.planner.papf.strategy.predict`, eq. 8
    (:func:`nodes.planner.papf.strategy.temporary_goal`) and the motion force give, bit for bit.

    ``apf``/``pp``: :class:`~nodes.planner.field.APFParams` and
    :class:`~nodes.planner.papf.strategy.PAPFParams`; ``quarks``: the ones already placed (or None).
    ``abandoned`` is one ``(n, i_max + 1, 2)`` array (a sequence of the abandoned paths).
    """
    c = kernel_params(apf, pp)
    pos = np.ascontiguousarray(pos, dtype=float)
    goal = np.ascontiguousarray(goal, dtype=float)
    obstacles = np.ascontiguousarray(obstacles, dtype=float).reshape(-1, 2)
    quarks = (_NO_QUARKS if quarks is None else
              np.ascontiguousarray(quarks, dtype=float).reshape(-1, 2))
    paths, n_paths, length, qbuf, lo, hi, resolved, reached, f_apf, qdist = _front(
        pos, goal, obstacles, quarks, c)
    path = paths[n_paths - 1, :length]
    eq8 = resolved or not pp.unresolved_global_goal
    if eq8:   # numpy's own rounding (BLAS) as in temporary_goal; norm(v) is sqrt(v . v)
        direction = f_apf if math.sqrt(f_apf.dot(f_apf)) > 0 else goal - pos
        pts = path[1:] if path.shape[0] > 1 else path
        u = direction / math.sqrt(direction.dot(direction))
        proj = (pts - pos) @ u
    else:     # no stagnation-free path after M repetitions: eq. 7 with the global goal
        pts, proj, u = path, _EMPTY, _EMPTY
    cube = np.maximum(qdist, c.ball) ** 3     # numpy's power, as quark_force
    target, force = _back(pos, pts, proj, u, eq8, goal, obstacles, qbuf[lo:hi], qdist, cube, c)
    return path, qbuf[lo:hi], paths[: n_paths - 1, : c.i_max + 1], bool(resolved), target, force


_EMPTY = np.zeros(0)
_NO_QUARKS = np.zeros((0, 2))
