"""IAPF's potential fields and their exact gradients (Jin et al., Symmetry 2024, Sec. 2.2, 3.1).

Pure scalar maths, used by :class:`nodes.planner.iapf.algorithm.IAPFCore` and its kernel
tests: road (eqs. 4-5, 18), attraction (eqs. 6-8, 19), safety distance (eq. 9), obstacles
(eqs. 10-12, 15-16, 20), our stop law. Each function returns the gradient and the
potential; the equations by function: docs/planners.md, "The algorithms in the code".
"""

from __future__ import annotations

import dataclasses
import math

from nodes.planner.road import Lanes, Track

# -- road (eqs. 4, 5, 18) ------------------------------------------------------------

def road_gradient(y: float, lanes: Lanes, k1: float, k2: float) -> tuple[float, float]:
    """``(U_road, dU_road/dY)`` at ``y`` (eq. 4: U_road = U_bound + U_center).

    Our reading of eq. 5 with Y the distance from the broken line (the two-lane road's
    centre), generalised to any lane count. With ``delta`` = y minus the centre of the
    lane holding y:

    - towards a solid line from the outer lanes' centres (U_bound): ``k1 delta^4``,
      gradient ``4 k1 delta^3`` (eq. 18's quartic branches, measured from the lane centre);
    - towards a broken line (U_center): ``k2 delta^2``, gradient ``2 k2 delta`` (eq. 18's
      middle branches with the sign that makes every lane centre a minimum); the ridge on
      a broken line is ``k2 d_w^2 / 4`` high.

    Beyond a solid line the quartic continues (eq. 5 holds it constant there, which would
    leave a vehicle that left the road without a way back).
    """
    lane = lanes.lane_of(y)
    delta = y - lanes.centre(lane)
    outer = (lane == 0 and delta < 0.0) or (lane == lanes.count - 1 and delta > 0.0)
    if outer:
        d3 = delta * delta * delta
        return k1 * d3 * delta, 4.0 * k1 * d3
    return k2 * delta * delta, 2.0 * k2 * delta


# -- attraction (eqs. 6-8, 19) ----------------------------------------------------------

def attraction_gradient(x: float, y: float, b1: float, b2: float, b3: float,
                        y_goal: float | None, half_period: float) -> tuple[float, float, float]:
    """``(U_att, dU/dX, dU/dY)`` of eq. 6: U_att = U_normal + U_goal.

    eq. 7 ``U_normal = -b1 X`` and eq. 8 ``U_goal = -b2 X - (D_g / pi) b3 cos(pi (Y - Y_goal) / D_g)``
    (the paper prints ``+b1 X`` and ``+b2 X``, which would push the vehicle backwards;
    Fig. 3b draws the field decreasing along X). ``D_g`` = ``half_period``: the paper's
    eq. 8 has ``d_w``, eq. 19 a ``D_g`` it never defines; its gradient is
    ``b3 sin(pi (Y - Y_goal) / D_g)`` (eq. 19's extra ``pi / d_w`` factor and its
    ``Y - Y_0 + D_g`` denominator do not follow from eq. 8; we use the derivative of eq. 8).
    ``y_goal=None``: no lane goal, only the pulls along X.
    """
    u = -(b1 + b2) * x
    gy = 0.0
    if y_goal is not None and b3 != 0.0:
        arg = math.pi * (y - y_goal) / half_period
        u -= half_period / math.pi * b3 * math.cos(arg)
        gy = b3 * math.sin(arg)
    return u, -(b1 + b2), gy


# -- obstacles (eqs. 9-12, 15, 16, 20) ------------------------------------------------

def safety_distance(v_host: float, v_obs: float, a_brake: float, margin: float) -> float:
    """Eq. 9: ``D_S = (v_c^2 - v_o^2) / (2 a_b) + S_m`` [m].

    A faster obstacle (``v_o > v_c``) gives a negative braking term; we keep S_m as the
    least range (ours: the paper's formula would drop an obstacle closing from behind
    once it is faster than the host).
    """
    return max(0.0, (v_host * v_host - v_obs * v_obs) / (2.0 * a_brake)) + margin


def gap(x: float, y: float, host_length: float, ob: Track) -> float:
    """[m] distance compared with D_S: centre distance less both half-lengths, >= 0 (ours)."""
    return max(0.0, math.hypot(x - ob.x, y - ob.y) - 0.5 * (host_length + ob.length))


def obstacle_gradient(x: float, y: float, ob: Track, gain: float, a_x: float, a_y: float,
                      literal_rotation: bool = False) -> tuple[float, float, float]:
    """``(U_obs, dU/dX, dU/dY)`` of one obstacle (eqs. 10, 11, 15, 16, 20).

    Eq. 11: ``U = gain * cos(arctan(dy / dx)) * exp(A_x R_x^2 + A_y R_y^2)`` with
    ``dx = x - x_o``, ``dy = y - y_o`` and ``cos(arctan(dy/dx)) = |dx| / d`` (``gain`` is ours:
    the printed field has amplitude 1; Fig. 4 says heavier vehicles have a higher peak).

    Rotation (eq. 10): the printed ``R_X = dx cos(phi) - dy sin(phi)``,
    ``R_Y = dx sin(phi) + dy cos(phi)`` turns the ellipse by ``-phi``, and the cosine factor
    stays in world axes. The text says the whole field "will rotate at the same angle as
    the vehicle heading angle" (Fig. 5), so by default we use obstacle-frame coordinates
    ``R_X = dx cos(phi) + dy sin(phi)``, ``R_Y = -dx sin(phi) + dy cos(phi)`` and the
    cosine of the bearing in that frame, ``|R_X| / d``. ``literal_rotation=True``: eqs. 10-11
    as printed.

    Gradient: eqs. 15-16 are the exact derivative of the printed field; eq. 20's second
    term has the wrong sign (``d/dY |dx| / d = -|dx| dy / d^3``). We use the exact
    derivative (tests compare it with finite differences).
    """
    dx, dy = x - ob.x, y - ob.y
    c, s = math.cos(ob.yaw), math.sin(ob.yaw)
    if not literal_rotation:
        s = -s
    rx = dx * c - dy * s
    ry = dx * s + dy * c
    e = gain * math.exp(a_x * rx * rx + a_y * ry * ry)
    d2 = dx * dx + dy * dy
    if d2 < 1e-18:
        return e, 0.0, 0.0
    d = math.sqrt(d2)
    # the cosine factor's axis: world x (printed) or the heading (ours), and its partials
    ax, px, py = (dx, 1.0, 0.0) if literal_rotation else (rx, c, -s)
    g = abs(ax) / d                                    # G_cos
    grx = 2.0 * a_x * rx * c + 2.0 * a_y * ry * s      # G_Rx (eq. 16)
    gry = -2.0 * a_x * rx * s + 2.0 * a_y * ry * c     # G_Ry (eq. 16)
    sg = 1.0 if ax > 0.0 else (-1.0 if ax < 0.0 else 0.0)
    d3 = d2 * d
    dgx = sg * px / d - abs(ax) * dx / d3
    dgy = sg * py / d - abs(ax) * dy / d3
    return g * e, e * (g * grx + dgx), e * (g * gry + dgy)


def traditional_gradient(x: float, y: float, ob: Track, k: float) -> tuple[float, float, float]:
    """``(U, dU/dX, dU/dY)`` of eq. 12, the traditional APF: ``U = k / (2 d)``."""
    dx, dy = x - ob.x, y - ob.y
    d2 = dx * dx + dy * dy
    if d2 < 1e-18:
        return math.inf, 0.0, 0.0
    d = math.sqrt(d2)
    f = -0.5 * k / (d2 * d)
    return 0.5 * k / d, f * dx, f * dy


# -- ours: the stop law and the headings of slow tracks (docs/planners.md "IAPF") ----------

def stop_deceleration(x: float, y: float, v: float, tracks, lanes: Lanes, host_length: float,
                      s_m: float, shift: float = 0.0) -> float:
    """[m/s^2] The deceleration that matches the speed of the closest-closing vehicle ahead in
    the host's lane ``s_m`` (S_m) short of it (the stop law, ours; docs/planners.md "IAPF").

    For each vehicle ahead (moved on by ``shift`` s) in the lane holding ``y`` and slower along
    X than ``v``: ``(v - v_oX)^2 / (2 (gap - S_m))`` (infinite once inside ``S_m``); the largest.
    Eq. 9's safety distance is the braking distance at ``a_b`` plus ``S_m``; eq. 25's field
    alone cannot brake a host at speed to a stop within it (its return term beats the field),
    so :meth:`nodes.planner.iapf.algorithm.IAPFCore.advance` brakes with this once it exceeds
    ``stop_decel_frac a_b``.
    """
    lane = lanes.lane_of(y)
    need = 0.0
    for ob in tracks:
        hx, hy = x - ob.vx * shift, y - ob.vy * shift
        closing = v - ob.vx
        if ob.x <= hx or closing <= 0.0 or lanes.lane_of(ob.y + y - hy) != lane:
            continue
        room = gap(hx, hy, host_length, ob) - s_m
        need = max(need, closing * closing / (2.0 * room) if room > 1e-9 else math.inf)
    return need


def road_headings(tracks, min_speed: float):
    """Tracks slower than ``min_speed`` [m/s] turned to head along the road (+X), the others to
    their direction of travel (ours: phi of eq. 10 is the vehicle's heading; a standing or
    creeping vehicle on a one-way road faces along it, and a tracker's heading of such a
    track is noise). ``min_speed <= 0``: the tracks as given."""
    if min_speed <= 0.0:
        return tracks
    out = []
    for ob in tracks:
        yaw = math.atan2(ob.vy, ob.vx) if ob.speed >= min_speed else 0.0
        out.append(ob if yaw == ob.yaw else dataclasses.replace(ob, yaw=yaw))
    return out
