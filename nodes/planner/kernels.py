"""Path-prediction kernel (PAPF Algorithm 1) — numba when available, numpy otherwise.

:func:`rollout` steps a point along the APF force (eq. 2, with top quarks eq. 7) by a
constant step ``Delta``; it is the hot loop of PAPF (up to (M + 1) * (lambda + lambda_stag)
/ Delta force evaluations over the whole scan per cycle).

The two implementations give **bit-identical** results (tested): the numpy one uses
:func:`nodes.planner.apf.coulomb_sum` (sequential sums, per-point arithmetic written out)
and scalar maths for the step; the numba one does the same operations in the same order
(no ``fastmath``, so no reassociation or fused multiply-add).
"""

from __future__ import annotations

import math

import numpy as np

from nodes.planner.apf import EPS_M, coulomb_sum

try:
    import numba
except ImportError:  # numba is optional (pyproject extra "fast")
    numba = None

HAVE_NUMBA = numba is not None


def _carrot(pos, goal, goal_range, out):
    """``out`` = ``goal``, or the point ``goal_range`` from ``pos`` towards it when farther."""
    d2 = 0.0
    for j in range(pos.shape[0]):
        d2 += (goal[j] - pos[j]) * (goal[j] - pos[j])
    dist = math.sqrt(d2)
    for j in range(pos.shape[0]):
        out[j] = goal[j] if dist <= goal_range else pos[j] + (goal[j] - pos[j]) * (goal_range / dist)
    return out


_carrot_jit = numba.njit(cache=True)(_carrot) if HAVE_NUMBA else None


def _force_numpy(pos, goal, g_goal, obstacles, g_obs, d_o, quarks, g_q, d_q, goal_range):
    f = np.zeros_like(pos)
    f = f - g_goal * coulomb_sum(pos, _carrot(pos, goal, goal_range, np.empty_like(pos))[None, :])
    f = f - g_obs * coulomb_sum(pos, obstacles, d_o)
    if quarks.shape[0]:
        f = f - g_q * coulomb_sum(pos, quarks, d_q)
    return f


def rollout_numpy(start, goal, g_goal, obstacles, g_obs, d_o, quarks, g_q, d_q, step, n_steps,
                  stop_radius, goal_range):
    """Numpy reference of :func:`rollout` (same arguments and result)."""
    dims = start.shape[0]
    path = np.empty((n_steps + 1, dims))
    path[0] = start
    for i in range(1, n_steps + 1):
        prev = path[i - 1]
        f = _force_numpy(prev, goal, g_goal, obstacles, g_obs, d_o, quarks, g_q, d_q, goal_range)
        n2 = 0.0
        for j in range(dims):
            n2 += f[j] * f[j]
        norm = math.sqrt(n2)
        scale = step / norm if norm > 0.0 else 0.0
        d2 = 0.0
        for j in range(dims):
            path[i, j] = prev[j] + f[j] * scale
            dj = path[i, j] - goal[j]
            d2 += dj * dj
        if d2 <= stop_radius * stop_radius:
            return path[: i + 1], True
    return path, False


if HAVE_NUMBA:
    @numba.njit(cache=True)
    def _coulomb_acc(pos, pts, d_max, gain, f):  # pragma: no cover - compiled
        dims = pos.shape[0]
        s = np.zeros(dims)
        d_max2 = d_max * d_max
        eps2 = EPS_M * EPS_M
        r = np.empty(dims)
        for k in range(pts.shape[0]):
            for j in range(dims):
                r[j] = pts[k, j] - pos[j]
            d2 = r[0] * r[0]
            for j in range(1, dims):
                d2 = d2 + r[j] * r[j]
            if d2 > eps2 and d2 <= d_max2:
                inv = 1.0 / (d2 * math.sqrt(d2))
                for j in range(dims):
                    s[j] += r[j] * inv
        for j in range(dims):
            f[j] = f[j] - gain * s[j]

    @numba.njit(cache=True)
    def _rollout_numba(start, goal, g_goal, obstacles, g_obs, d_o, quarks, g_q, d_q, step,
                       n_steps, stop_radius, goal_range):  # pragma: no cover - compiled
        dims = start.shape[0]
        path = np.empty((n_steps + 1, dims))
        path[0] = start
        goal2 = np.empty((1, dims))
        f = np.empty(dims)
        for i in range(1, n_steps + 1):
            prev = path[i - 1]
            f[:] = 0.0
            _carrot_jit(prev, goal, goal_range, goal2[0])
            _coulomb_acc(prev, goal2, np.inf, g_goal, f)
            _coulomb_acc(prev, obstacles, d_o, g_obs, f)
            if quarks.shape[0]:
                _coulomb_acc(prev, quarks, d_q, g_q, f)
            n2 = 0.0
            for j in range(dims):
                n2 += f[j] * f[j]
            norm = math.sqrt(n2)
            scale = step / norm if norm > 0.0 else 0.0
            d2 = 0.0
            for j in range(dims):
                path[i, j] = prev[j] + f[j] * scale
                dj = path[i, j] - goal[j]
                d2 += dj * dj
            if d2 <= stop_radius * stop_radius:
                return path[: i + 1], True
        return path, False


def _tail_python(path, first, radius):
    """Mean of ``path[first:]`` and whether every point lies within ``radius`` of it."""
    n, dims = path.shape[0] - first, path.shape[1]
    mean = np.zeros(dims)
    if n <= 0:
        return False, mean
    for k in range(first, path.shape[0]):
        for j in range(dims):
            mean[j] += path[k, j]
    for j in range(dims):
        mean[j] = mean[j] / n
    for k in range(first, path.shape[0]):
        d2 = 0.0
        for j in range(dims):
            dj = path[k, j] - mean[j]
            d2 += dj * dj
        if d2 > radius * radius:
            return False, mean
    return True, mean


_tail_numba = numba.njit(cache=True)(_tail_python) if HAVE_NUMBA else None


def tail_stagnation(path: np.ndarray, first: int, radius: float,
                    use_numba: bool = True) -> tuple[bool, np.ndarray]:
    """PAPF Sec. III-B: are all of ``path[first:]`` within ``radius`` of their mean? (and the mean)."""
    path = np.ascontiguousarray(path, dtype=float)
    if use_numba and HAVE_NUMBA:
        return _tail_numba(path, int(first), float(radius))
    return _tail_python(path, int(first), float(radius))


def rollout(start, goal, g_goal: float, obstacles, g_obs: float, d_o: float, quarks,
            g_q: float, d_q: float, step: float, n_steps: int, stop_radius: float,
            use_numba: bool = True, goal_range: float = math.inf) -> tuple[np.ndarray, bool]:
    """Algorithm 1: ``path[0] = start``, ``path[i] = path[i-1] + step * F/|F|`` for ``n_steps``.

    ``F = -g_goal S(goal) - g_obs S(obstacles within d_o) - g_q S(quarks within d_q)`` with
    ``S`` = :func:`coulomb_sum` (gains are ``k q_V q_X``). A goal farther than ``goal_range``
    pulls as one ``goal_range`` away in its direction (the PAPF prediction's pull range). Stops early, returning
    ``(path[:i+1], True)``, once a point is within ``stop_radius`` of the goal. Zero force:
    the point stays (a stagnation the caller detects).
    """
    args = (np.ascontiguousarray(start, dtype=float), np.ascontiguousarray(goal, dtype=float),
            float(g_goal), np.ascontiguousarray(obstacles, dtype=float).reshape(-1, len(start)),
            float(g_obs), float(d_o),
            np.ascontiguousarray(quarks, dtype=float).reshape(-1, len(start)), float(g_q),
            float(d_q), float(step), int(n_steps), float(stop_radius), float(goal_range))
    if use_numba and HAVE_NUMBA:
        return _rollout_numba(*args)
    return rollout_numpy(*args)
