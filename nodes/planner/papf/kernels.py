"""Path-prediction kernel (PAPF Algorithm 1) — numba when available, numpy otherwise.

:func:`rollout` steps a point along the APF force (eq. 2, with top quarks eq. 7) by a
constant step ``Delta``; it is the hot loop of PAPF (up to (M + 1) * (lambda + lambda_stag)
/ Delta force evaluations over the whole scan per cycle).

Every kernel takes the cycle's gains and counts as one
:class:`~nodes.planner.papf.params.KernelParams` (``kp``), built once per settings by
:func:`~nodes.planner.papf.params.kernel_params`.

The two implementations give **bit-identical** results (tested): the numpy one uses
:func:`nodes.planner.field.coulomb_sum` (sequential sums, per-point arithmetic written out)
and scalar maths for the step; the numba one does the same operations in the same order
(no ``fastmath``, so no reassociation or fused multiply-add).
"""

from __future__ import annotations

import math

import numpy as np

from common.optional import HAVE_NUMBA, numba_or_none
from nodes.planner.field import EPS_M, coulomb_sum
from nodes.planner.papf.params import KernelParams, kernel_params  # noqa: F401  (re-exported)

numba = numba_or_none()   # None without the extra "fast": the numpy twins run


def _carrot(pos, goal, goal_range, out):
    """``out`` = ``goal``, or the point ``goal_range`` from ``pos`` towards it when farther."""
    d2 = 0.0
    for j in range(pos.shape[0]):
        d2 += (goal[j] - pos[j]) * (goal[j] - pos[j])
    dist = math.sqrt(d2)
    for j in range(pos.shape[0]):
        out[j] = goal[j] if dist <= goal_range else pos[j] + (goal[j] - pos[j]) * (goal_range / dist)
    return out


_carrot_jit = numba.njit(cache=True, error_model="numpy")(_carrot) if HAVE_NUMBA else None


def _advance(prev, f, step, goal, out):
    """``out`` = ``prev`` + ``step`` [m] along ``f`` (stays at ``prev`` for zero force); its
    squared distance to ``goal`` [m^2]. One step of Algorithm 1, for both paths."""
    n2 = 0.0
    for j in range(prev.shape[0]):
        n2 += f[j] * f[j]
    norm = math.sqrt(n2)
    scale = step / norm if norm > 0.0 else 0.0
    d2 = 0.0
    for j in range(prev.shape[0]):
        out[j] = prev[j] + f[j] * scale
        dj = out[j] - goal[j]
        d2 += dj * dj
    return d2


_advance_jit = numba.njit(cache=True, error_model="numpy")(_advance) if HAVE_NUMBA else None


def _force_numpy(pos, goal, obstacles, quarks, kp):
    f = np.zeros_like(pos)
    f = f - kp.g_goal * coulomb_sum(pos, _carrot(pos, goal, kp.pull_range, np.empty_like(pos))[None, :])
    f = f - kp.g_obs * coulomb_sum(pos, obstacles, kp.d_o)
    if quarks.shape[0]:
        f = f - kp.g_q * coulomb_sum(pos, quarks, kp.d_q)
    return f


def rollout_numpy(start, goal, obstacles, quarks, kp, n_steps, stop_radius):
    """Numpy reference of :func:`rollout` (same arguments and result)."""
    dims = start.shape[0]
    path = np.empty((n_steps + 1, dims))
    path[0] = start
    for i in range(1, n_steps + 1):
        prev = path[i - 1]
        f = _force_numpy(prev, goal, obstacles, quarks, kp)
        if _advance(prev, f, kp.step, goal, path[i]) <= stop_radius * stop_radius:
            return path[: i + 1], True
    return path, False


# Obstacle candidates: a predicted point moves at most Delta per step, so only the points
# within d_o + B * Delta of a block's first point can be within d_o of any of the block's B
# points. The kernel selects such candidates every CANDIDATE_BLOCK steps from all points and
# every CANDIDATE_SUBBLOCK steps from those. The skipped points would fail the d_o test
# anyway: the sums, and so the results, are unchanged; only the time shrinks.
CANDIDATE_BLOCK = 8
CANDIDATE_SUBBLOCK = 2


if HAVE_NUMBA:
    # error_model="numpy": a division by zero gives inf instead of raising, so no check per
    # division (every division here is guarded; the results are the same).
    _jit = numba.njit(cache=True, error_model="numpy")

    @_jit
    def _coulomb_acc(pos, pts, d_max, gain, f):  # pragma: no cover - compiled
        dims = pos.shape[0]
        d_max2 = d_max * d_max
        eps2 = EPS_M * EPS_M
        if dims == 2:  # scalars, no scratch arrays: the same operations in the same order
            sx, sy, px, py = 0.0, 0.0, pos[0], pos[1]
            for k in range(pts.shape[0]):
                rx, ry = pts[k, 0] - px, pts[k, 1] - py
                d2 = rx * rx
                d2 = d2 + ry * ry
                if d2 > eps2 and d2 <= d_max2:
                    inv = 1.0 / (d2 * math.sqrt(d2))
                    sx += rx * inv
                    sy += ry * inv
            f[0] = f[0] - gain * sx
            f[1] = f[1] - gain * sy
            return
        s = np.zeros(dims)
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

    @_jit
    def _near(pos, pts, radius, near):  # pragma: no cover - compiled
        """Copy the points within ``radius`` of ``pos`` (in order) into ``near``; their count."""
        n = 0
        r2 = radius * radius
        dims = pos.shape[0]
        if dims == 2:
            px, py = pos[0], pos[1]
            for k in range(pts.shape[0]):
                x, y = pts[k, 0], pts[k, 1]
                if (x - px) * (x - px) + (y - py) * (y - py) <= r2:
                    near[n, 0], near[n, 1] = x, y
                    n += 1
            return n
        for k in range(pts.shape[0]):
            d2 = 0.0
            for j in range(dims):
                d2 += (pts[k, j] - pos[j]) * (pts[k, j] - pos[j])
            if d2 <= r2:
                for j in range(dims):
                    near[n, j] = pts[k, j]
                n += 1
        return n

    @_jit
    def _rollout_into(path, scratch, start, goal, obstacles, quarks, kp, n_steps,
                      stop_radius):  # pragma: no cover - compiled
        """Algorithm 1 into ``path`` (n_steps + 1, D); returns (points written, reached).

        ``scratch`` = (``near`` (2, K, D), ``goal2`` (1, D), ``f`` (D,)): buffers.
        """
        near, goal2, f = scratch
        step = kp.step
        path[0] = start
        reach = kp.d_o + CANDIDATE_BLOCK * step + 1e-6
        reach_sub = kp.d_o + CANDIDATE_SUBBLOCK * step + 1e-6
        n_block = n_near = 0
        for i in range(1, n_steps + 1):
            prev = path[i - 1]
            if (i - 1) % CANDIDATE_BLOCK == 0:
                n_block = _near(prev, obstacles, reach, near[0])
            if (i - 1) % CANDIDATE_SUBBLOCK == 0:
                n_near = _near(prev, near[0, :n_block], reach_sub, near[1])
            f[:] = 0.0
            _carrot_jit(prev, goal, kp.pull_range, goal2[0])
            _coulomb_acc(prev, goal2, np.inf, kp.g_goal, f)
            _coulomb_acc(prev, near[1, :n_near], kp.d_o, kp.g_obs, f)
            if quarks.shape[0]:
                _coulomb_acc(prev, quarks, kp.d_q, kp.g_q, f)
            if _advance_jit(prev, f, step, goal, path[i]) <= stop_radius * stop_radius:
                return i + 1, True
        return n_steps + 1, False

    @_jit
    def _scratch(obstacles, dims):  # pragma: no cover - compiled
        """The buffers :func:`_rollout_into` works in."""
        return np.empty((2, *obstacles.shape)), np.empty((1, dims)), np.empty(dims)

    @_jit
    def _rollout_numba(start, goal, obstacles, quarks, kp, n_steps,
                       stop_radius):  # pragma: no cover - compiled
        dims = start.shape[0]
        path = np.empty((n_steps + 1, dims))
        n, reached = _rollout_into(path, _scratch(obstacles, dims), start, goal, obstacles, quarks,
                                   kp, n_steps, stop_radius)
        return path[:n], reached


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


_tail_numba = numba.njit(cache=True, error_model="numpy")(_tail_python) if HAVE_NUMBA else None


def tail_stagnation(path: np.ndarray, first: int, radius: float,
                    use_numba: bool = True) -> tuple[bool, np.ndarray]:
    """PAPF Sec. III-B: are all of ``path[first:]`` within ``radius`` of their mean? (and the mean)."""
    path = np.ascontiguousarray(path, dtype=float)
    if use_numba and HAVE_NUMBA:
        return _tail_numba(path, int(first), float(radius))
    return _tail_python(path, int(first), float(radius))


def _arrays(start, goal, obstacles, quarks) -> tuple:
    """The kernels' array arguments: contiguous float64, points as (K, D)."""
    dims = len(start)
    return (np.ascontiguousarray(start, dtype=float), np.ascontiguousarray(goal, dtype=float),
            np.ascontiguousarray(obstacles, dtype=float).reshape(-1, dims),
            np.ascontiguousarray(quarks, dtype=float).reshape(-1, dims))


def rollout(start, goal, obstacles, quarks, kp: KernelParams, n_steps: int, stop_radius: float,
            use_numba: bool = True) -> tuple[np.ndarray, bool]:
    """Algorithm 1: ``path[0] = start``, ``path[i] = path[i-1] + Delta * F/|F|`` for ``n_steps``.

    ``F = -g_goal S(goal) - g_obs S(obstacles within d_o) - g_q S(quarks within d_q)`` with
    ``S`` = :func:`coulomb_sum` (gains are ``k q_V q_X``, all from ``kp``). A goal farther
    than ``kp.pull_range`` pulls as one that far away in its direction (the PAPF
    prediction's pull range). Stops early, returning ``(path[:i+1], True)``, once a point is
    within ``stop_radius`` of the goal. Zero force: the point stays (a stagnation the
    caller detects).
    """
    args = (*_arrays(start, goal, obstacles, quarks), kp, int(n_steps), float(stop_radius))
    if use_numba and HAVE_NUMBA:
        return _rollout_numba(*args)
    return rollout_numpy(*args)


def _predict_python(start, goal, obstacles, quarks, kp):
    """Numpy reference of :func:`predict_paths` (same arguments and result)."""
    i_max, max_quarks = kp.i_max, kp.max_quarks
    quarks = quarks[max(0, quarks.shape[0] - max_quarks):]
    abandoned = []
    while True:
        path, reached = rollout_numpy(start, goal, obstacles, quarks, kp, i_max + kp.n_stag, kp.step)
        if reached:
            return path, quarks, abandoned, True, True
        stuck, mean = _tail_python(path, i_max + 1, kp.stag_radius)
        if not stuck:
            return path[: i_max + 1], quarks, abandoned, True, False
        if len(abandoned) >= max_quarks or max_quarks <= 0:
            return path[: i_max + 1], quarks, abandoned, False, False
        abandoned.append(path[: i_max + 1])
        quarks = np.vstack([quarks[max(0, quarks.shape[0] - max_quarks + 1):], mean])


if HAVE_NUMBA:
    @_jit
    def _predict_numba(start, goal, obstacles, quarks, kp):  # pragma: no cover - compiled
        """:func:`_predict_python` with every rollout written into one buffer.

        Returns (paths, n_paths, last length, quark buffer, first quark, end quark, resolved, reached):
        ``paths[:n_paths - 1]`` are the abandoned ones (their first i_max + 1 points).
        """
        dims = start.shape[0]
        i_max, max_quarks = kp.i_max, kp.max_quarks
        n_steps = i_max + kp.n_stag
        m = max(max_quarks, 0)
        paths = np.empty((m + 1, n_steps + 1, dims))
        qbuf = np.empty((quarks.shape[0] + m + 1, dims))
        qbuf[: quarks.shape[0]] = quarks
        lo, hi = max(0, quarks.shape[0] - max_quarks), quarks.shape[0]
        scratch = _scratch(obstacles, dims)
        k = 0
        while True:
            n, reached = _rollout_into(paths[k], scratch, start, goal, obstacles, qbuf[lo:hi], kp,
                                       n_steps, kp.step)
            if reached:
                return paths, k + 1, n, qbuf, lo, hi, True, True
            stuck, mean = _tail_numba(paths[k], i_max + 1, kp.stag_radius)
            if not stuck:
                return paths, k + 1, i_max + 1, qbuf, lo, hi, True, False
            if k >= max_quarks or max_quarks <= 0:
                return paths, k + 1, i_max + 1, qbuf, lo, hi, False, False
            k += 1
            lo += max(0, hi - lo - max_quarks + 1)
            qbuf[hi] = mean
            hi += 1


def predict_paths(start, goal, obstacles, quarks, kp: KernelParams,
                  use_numba: bool = True) -> tuple[np.ndarray, np.ndarray, list, bool, bool]:
    """PAPF Algorithm 1 with the top-quark loop of Sec. III-B, in one call (one kernel call).

    Roll out ``i_max + n_stag`` steps (:func:`rollout`, stopping within ``step`` of the goal);
    if the last ``n_stag`` points lie within ``stag_radius`` of their mean
    (:func:`tail_stagnation`) the prediction stagnated: a top quark goes at that mean (the
    oldest giving way beyond ``max_quarks``), the path is abandoned and the rollout repeats,
    at most ``max_quarks`` times (every number from ``kp``). Returns ``(path, quarks,
    abandoned, resolved, reached)``: the last path (its first ``i_max + 1`` points unless it
    reached the goal), the quarks in use (oldest first), the abandoned paths, False if still
    stagnating after ``max_quarks`` repetitions, True if the path reached the goal.
    """
    args = (*_arrays(start, goal, obstacles, quarks), kp)
    if not (use_numba and HAVE_NUMBA):
        return _predict_python(*args)
    paths, n_paths, length, qbuf, lo, hi, resolved, reached = _predict_numba(*args)
    abandoned = [paths[k, : kp.i_max + 1] for k in range(n_paths - 1)]
    return paths[n_paths - 1, :length], qbuf[lo:hi], abandoned, bool(resolved), bool(reached)


if HAVE_NUMBA:
    @_jit
    def _field_numba(pos, goal, obstacles, kp):  # pragma: no cover - compiled
        f = np.zeros(pos.shape[0])
        goal2 = np.empty((1, pos.shape[0]))
        goal2[0] = goal
        _coulomb_acc(pos, goal2, np.inf, kp.g_goal, f)
        _coulomb_acc(pos, obstacles, kp.d_o, kp.g_obs, f)
        return f


def field_force(pos, goal, obstacles, kp: KernelParams, use_numba: bool = True) -> np.ndarray:
    """Eq. 2 at ``pos``: ``-g_goal S(goal) - g_obs S(obstacles within d_o)`` (S = coulomb_sum).

    Bit for bit :func:`nodes.planner.field.apf_force` without extra repulsors (gains
    ``k_VG q_V q_G`` and ``k_VO q_V q_O`` from ``kp``), one compiled call instead of numpy's dozen.
    """
    pos = np.ascontiguousarray(pos, dtype=float)
    goal = np.ascontiguousarray(goal, dtype=float)
    obstacles = np.ascontiguousarray(obstacles, dtype=float).reshape(-1, pos.shape[0])
    if use_numba and HAVE_NUMBA:
        return _field_numba(pos, goal, obstacles, kp)
    f = np.zeros_like(pos)
    f = f - kp.g_goal * coulomb_sum(pos, goal[None, :])
    return f - kp.g_obs * coulomb_sum(pos, obstacles, kp.d_o)
