"""IAPF prediction kernel (Algorithm 1, Step 1) — numba when available, plain Python otherwise.

:func:`rollout` advances the host ``n`` steps with the whole IAPF step of
:class:`nodes.planner.iapf.algorithm.IAPFCore.advance` — eqs. 4-5/18 (road), 6-8/19 (attraction), 9
(safety cut-off), 10-11/15-16/20 (obstacles; eq. 12 for the baseline), 25-26 (speed),
21-22 (heading and position) — written out in one loop over plain floats and arrays, so
that numba can compile the very same source. It is the hot loop of IAPF (``f_step``
steps per planning cycle). Tests compare it with ``IAPFCore.advance`` step by step.
"""

from __future__ import annotations

import math

import numpy as np

from common.optional import HAVE_NUMBA, numba_or_none

numba = numba_or_none()   # None without the extra "fast": the numpy twins run

# params vector layout (see pack_params)
(K1, K2, B1, B2, AX, AY, ETA1, ETA2, AB, SM, GAIN, MASS, AMAX, VMAX, VC, HALF, HMAX, YRATE,
 HLEN, LITERAL, TRAD, KTRAD, BRAKE, STOP) = range(24)
# obstacle row layout: x, y, yaw, vx, vy, speed, length
OBS_COLS = 7


def _road_grad_py(y, y_min, width, count, k1, k2):
    lane = int(math.floor((y - y_min) / width))
    lane = min(max(lane, 0), count - 1)
    delta = y - (y_min + (lane + 0.5) * width)
    if (lane == 0 and delta < 0.0) or (lane == count - 1 and delta > 0.0):
        return 4.0 * k1 * delta * delta * delta
    return 2.0 * k2 * delta


def _obstacle_grad_py(hx, hy, ob, prm):
    """dU/dX, dU/dY of one obstacle row at the host position (hx, hy)."""
    dx, dy = hx - ob[0], hy - ob[1]
    d2 = dx * dx + dy * dy
    if prm[TRAD] > 0.5:
        if d2 < 1e-18:
            return 0.0, 0.0
        d = math.sqrt(d2)
        f = -0.5 * prm[KTRAD] / (d2 * d)
        return f * dx, f * dy
    c, s = math.cos(ob[2]), math.sin(ob[2])
    literal = prm[LITERAL] > 0.5
    if not literal:
        s = -s
    rx = dx * c - dy * s
    ry = dx * s + dy * c
    a_x, a_y = prm[AX], prm[AY]
    e = prm[GAIN] * math.exp(a_x * rx * rx + a_y * ry * ry)
    if d2 < 1e-18:
        return 0.0, 0.0
    d = math.sqrt(d2)
    if literal:
        ax, px, py = dx, 1.0, 0.0
    else:
        ax, px, py = rx, c, -s
    g = abs(ax) / d
    grx = 2.0 * a_x * rx * c + 2.0 * a_y * ry * s
    gry = -2.0 * a_x * rx * s + 2.0 * a_y * ry * c
    sg = 1.0 if ax > 0.0 else (-1.0 if ax < 0.0 else 0.0)
    d3 = d2 * d
    dgx = sg * px / d - abs(ax) * dx / d3
    dgy = sg * py / d - abs(ax) * dy / d3
    return e * (g * grx + dgx), e * (g * gry + dgy)


def _stop_need_py(x, y, v, obs, prm, y_min, width, count, shift):
    """The stop law's deceleration (:func:`nodes.planner.iapf.fields.stop_deceleration`)."""
    lane = min(max(int(math.floor((y - y_min) / width)), 0), count - 1)
    need = 0.0
    for i in range(obs.shape[0]):
        ob = obs[i]
        hx, hy = x - ob[3] * shift, y - ob[4] * shift
        closing = v - ob[3]
        ob_lane = min(max(int(math.floor((ob[1] + y - hy - y_min) / width)), 0), count - 1)
        if ob[0] <= hx or closing <= 0.0 or ob_lane != lane:
            continue
        room = max(0.0, math.sqrt((hx - ob[0]) ** 2 + (hy - ob[1]) ** 2)
                   - 0.5 * (prm[HLEN] + ob[6])) - prm[SM]
        need = max(need, closing * closing / (2.0 * room) if room > 1e-9 else math.inf)
    return need


# the helpers are compiled when numba is there (the Python rollout can call them too)
_road_grad = numba.njit(cache=True)(_road_grad_py) if HAVE_NUMBA else _road_grad_py
_obstacle_grad = numba.njit(cache=True)(_obstacle_grad_py) if HAVE_NUMBA else _obstacle_grad_py
_stop_need = numba.njit(cache=True)(_stop_need_py) if HAVE_NUMBA else _stop_need_py


def _rollout(state, obs, prm, road, y_goal, has_goal, b3, dt, n, shift0, out):
    """Advance ``state`` = (x, y, v, yaw) ``n`` steps of ``dt``; row k of ``out`` = state after
    k + 1 steps, with the obstacles shifted by ``shift0 + k dt`` at constant velocity."""
    x, y, v, yaw = state[0], state[1], state[2], state[3]
    y_min, width, count = road[0], road[1], int(road[2])
    trad = prm[TRAD] > 0.5
    for k in range(n):
        shift = shift0 + k * dt
        gy = 0.0
        if has_goal and b3 != 0.0:
            gy = b3 * math.sin(math.pi * (y - y_goal) / prm[HALF])
        if count > 0:
            gy += _road_grad(y, y_min, width, count, prm[K1], prm[K2])
        ox = oy = 0.0
        for i in range(obs.shape[0]):
            ob = obs[i]
            hx, hy = x - ob[3] * shift, y - ob[4] * shift
            if not trad:
                gap = max(0.0, math.sqrt((hx - ob[0]) ** 2 + (hy - ob[1]) ** 2)
                          - 0.5 * (prm[HLEN] + ob[6]))
                ds = max(0.0, (v * v - ob[5] * ob[5]) / (2.0 * prm[AB])) + prm[SM]
                if gap >= ds:
                    continue
            ux, uy = _obstacle_grad(hx, hy, ob, prm)
            ox -= ux
            oy -= uy
        fx = prm[B1] + prm[B2] + ox
        fy = -gy + oy
        if not trad:
            dv = prm[VC] - v
            back = prm[ETA2] * dv * dv * dv
            if prm[BRAKE] > 0.5 and ox < 0.0:
                back = min(back, 0.0)
            accel = (prm[ETA1] * ox + back) / prm[MASS]
            if prm[STOP] > 0.0 and count > 0:
                need = _stop_need(x, y, v, obs, prm, y_min, width, count, shift)
                if need > prm[STOP] * prm[AB]:
                    accel = min(accel, -need)
            accel = min(max(accel, -prm[AB]), prm[AMAX])
            v = min(max(v + accel * dt, 0.0), prm[VMAX])
        new_yaw = min(max(math.atan2(fy, fx), -prm[HMAX]), prm[HMAX])
        if prm[YRATE] > 0.0:
            turn = prm[YRATE] * dt
            new_yaw = min(max(new_yaw, yaw - turn), yaw + turn)
        yaw = new_yaw
        x = x + math.cos(yaw) * v * dt
        y = y + math.sin(yaw) * v * dt
        out[k, 0], out[k, 1], out[k, 2], out[k, 3] = x, y, v, yaw
    return out


_rollout_jit = numba.njit(cache=True)(_rollout) if HAVE_NUMBA else None


def pack_params(p) -> np.ndarray:
    """:class:`nodes.planner.iapf.algorithm.IAPFParams` -> the kernel's params vector."""
    vals = [p.k1, p.k2, p.b1, p.b2, p.a_x, p.a_y, p.eta1, p.eta2, p.a_b, p.s_m, p.obstacle_gain,
            p.mass, p.a_max, p.v_max_factor * p.v_cruise, p.v_cruise, 0.0,
            math.radians(p.heading_max_deg), math.radians(p.yaw_rate_max_deg), p.host_length,
            float(p.literal_rotation), float(p.traditional), p.k_trad, float(p.brake_priority),
            p.stop_decel_frac]
    return np.array(vals, dtype=np.float64)


def pack_obstacles(tracks) -> np.ndarray:
    """Tracks -> (K, 7) rows x, y, yaw, vx, vy, speed, length."""
    arr = np.empty((len(tracks), OBS_COLS))
    for i, ob in enumerate(tracks):
        arr[i] = (ob.x, ob.y, ob.yaw, ob.vx, ob.vy, ob.speed, ob.length)
    return arr


def rollout(state, obs: np.ndarray, prm: np.ndarray, road, y_goal: float | None, b3: float,
            dt: float, n: int, use_numba: bool = True) -> np.ndarray:
    """(n, 4) states x, y, v, yaw after each of ``n`` steps (see :func:`_rollout`); ``prm``
    from :func:`pack_params` with ``prm[HALF]`` = the lane goal's half period [m]; ``road`` =
    (y_min, width, count) or count 0 for none."""
    out = np.empty((n, 4))
    args = (np.asarray(state, dtype=np.float64), obs, prm, np.asarray(road, dtype=np.float64),
            0.0 if y_goal is None else float(y_goal), y_goal is not None, float(b3), float(dt),
            int(n), 0.0, out)
    if use_numba and HAVE_NUMBA:
        return _rollout_jit(*args)
    return _rollout(*args)
