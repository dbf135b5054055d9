"""IAPF's planning core (Jin et al., Symmetry 16 (2024) 106): one step of the host particle.

Safety filter (eq. 9), prediction and temporary lane goal (Algorithm 1), fields (eq. 13),
speed (eqs. 25-26), motion (eqs. 21-22). :class:`IAPFCore` is used by the planner's IAPF
strategy (:mod:`nodes.planner.iapf.strategy`) and the offline car simulation
(papf/offline/car.py); ``traditional=True`` is the paper's baseline. Step by step:
docs/planners.md, "The algorithms in the code".
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from nodes.planner.iapf.fields import (
    Lanes,
    attraction_gradient,
    gap,
    obstacle_gradient,
    road_gradient,
    road_headings,
    safety_distance,
    stop_deceleration,
    traditional_gradient,
)
from nodes.planner.lazy import lazy_module

# the rollout kernel (and numba) loads when an IAPF core is built, not with the registry
iapf_kernel = lazy_module("nodes.planner.iapf.kernels")


@dataclass(frozen=True)
class IAPFParams:
    """IAPF parameters at car scale. Table 1 values unless marked (ours)."""

    k1: float = 3.397            # road boundary amplitude (Table 1)
    k2: float = 5.809            # lane centre amplitude (Table 1)
    b1: float = 20.0             # cruise pull along +x (Table 1)
    b2: float = 0.15             # goal pull along +x (Table 1)
    b3: float = 1.52             # lane-goal amplitude (Table 1)
    a_x: float = -0.01           # [1/m^2] size coefficient along the heading (ours; Table 1: -0.15)
    a_y: float = -0.2            # [1/m^2] obstacle size coefficient across (Table 1)
    eta1: float = 0.63           # eq. 25 force weight (Table 1)
    eta2: float = 0.25           # eq. 25 return-to-cruise weight (Table 1)
    step_s: float = 0.02         # [s] t, planning step (Table 1)
    horizon_s: float = 5.0       # [s] T, trajectory horizon of one plan (Table 1)
    s_m: float = 5.0             # [m] safety margin of eq. 9 (Table 1)
    a_b: float = 6.0             # [m/s^2] maximum braking (Table 1)
    f_step: int = 20             # future steps of the prediction (Table 1)
    c_f: int = 5                 # local-minimum sensitivity (Table 1)
    t_c: float = 0.8             # [s] temporary goal lifetime (ours; Table 1: 0.4)
    v_cruise: float = 10.0       # [m/s] V_c, 36 km/h (Sec. 4.1)
    obstacle_gain: float = 100.0  # amplitude of eq. 11 (ours; 1 in the paper's formula)
    mass: float = 1.0            # [kg] m of eq. 25 (ours: not in Table 1)
    a_max: float = 3.0           # [m/s^2] acceleration limit (ours)
    v_max_factor: float = 1.2    # v <= factor * V_c (ours: "accelerate when passing")
    predict_step_s: float = 0.15  # [s] step of the low-resolution prediction (ours)
    goal_half_period_lanes: float = 2.0  # D_g / d_w of eqs. 8, 19 (ours; 1 = eq. 8 as printed)
    b3_temp: float = 70.0        # lane-goal amplitude while a temporary goal is active (ours)
    heading_max_deg: float = 30.0  # [deg] |phi_E| limit about +x (ours; 90 = none)
    yaw_rate_max_deg: float = 90.0  # [deg/s] heading change limit (ours; 0 = none, as eq. 21)
    host_length: float = 4.5     # [m] host footprint along its heading (ours: a car)
    host_width: float = 1.8      # [m] (ours)
    literal_rotation: bool = False  # eq. 10 as printed (turns the field by -phi)
    prediction: bool = True      # Algorithm 1 on (off: "IAPF without prediction", Table 2)
    traditional: bool = False    # the traditional APF baseline (eq. 12, constant speed)
    k_trad: float = 3000.0       # eq. 12 k of the baseline (ours)
    brake_priority: bool = False  # an obstacle pushing back suspends eq. 25's return to V_c (ours)
    stop_decel_frac: float = 0.0  # stop law: brake as needed above this * a_b (ours; 0 = off)
    node_stop_decel_frac: float = 0.5  # stop_decel_frac in the planner node (ours; 0 = off)
    heading_min_speed: float = 2.5  # [m/s] slower tracks head along the road (ours; 0 = off)
    follow_min_frac: float = 0.5  # leader slower than this * V_c: change lanes if free (ours; 0 = off)
    goal_lane_s: float = 6.0     # [s] of cruise before the goal: pull to its lane (ours; 0 = off)
    lane_width_ref: float = 4.0  # [m] the lane width d_w these values are for (Table 1)
    cruise_speed: float = 0.3    # [m/s] V_c of the planner node on the run's road (ours, ROSbot)


# Table 1 read literally (``--preset paper``): every value of ours that replaces a Table 1
# value goes back, every addition of ours is switched off.
PAPER_PRESET = {"a_x": -0.15, "t_c": 0.4, "obstacle_gain": 1.0, "predict_step_s": 0.02,
                "goal_half_period_lanes": 1.0, "b3_temp": 1.52, "heading_max_deg": 90.0,
                "yaw_rate_max_deg": 0.0, "literal_rotation": True, "follow_min_frac": 0.0,
                "goal_lane_s": 0.0, "stop_decel_frac": 0.0, "node_stop_decel_frac": 0.0,
                "heading_min_speed": 0.0}

_LENGTH_TIMES = {"s_m": (1, 0), "host_length": (1, 0), "host_width": (1, 0),
                 "lane_width_ref": (1, 0), "k_trad": (1, 0),
                 "step_s": (0, 1), "horizon_s": (0, 1), "goal_lane_s": (0, 1), "t_c": (0, 1),
                 "predict_step_s": (0, 1),
                 "yaw_rate_max_deg": (0, -1), "v_cruise": (1, -1), "heading_min_speed": (1, -1), "a_b": (1, -2),
                 "a_max": (1, -2), "k1": (-4, 0), "k2": (-2, 0), "b1": (-1, 0), "b2": (-1, 0),
                 "b3": (-1, 0), "b3_temp": (-1, 0), "a_x": (-2, 0), "a_y": (-2, 0),
                 "eta1": (2, -2), "eta2": (-2, 1)}


def scaled(p: IAPFParams, length: float, time: float) -> IAPFParams:
    """The same planner on a world ``length`` times as large and ``time`` times as slow.

    A similarity transform (ours; docs/planners.md "ROSbot scale"): potentials stay, every
    length is multiplied by ``length`` and every time by ``time``, so speeds scale by
    ``length / time`` and accelerations by ``length / time^2``. Each coefficient follows
    from its equation's units — e.g. ``k1 delta^4`` -> ``k1 / length^4``, ``b1 X`` ->
    ``b1 / length``, eq. 25 ``eta1 F_ox / m`` (F ~ 1/length) -> ``eta1 length^2 / time^2``,
    ``eta2 (V_c - v)^3`` -> ``eta2 time / length^2``. A trajectory of the scaled planner is
    the original one scaled, point by point.
    """
    changes = {name: getattr(p, name) * length ** ln * time ** tn
               for name, (ln, tn) in _LENGTH_TIMES.items()}
    return dataclasses.replace(p, **changes)


@dataclass
class HostState:
    """The planned vehicle state of eq. 2: position [m], speed [m/s], heading [rad]."""

    x: float
    y: float
    v: float
    yaw: float = 0.0


@dataclass
class StepInfo:
    """What one step decided (for planner/state, plots and tests)."""

    force: tuple[float, float] = (0.0, 0.0)
    f_ox: float = 0.0
    accel: float = 0.0
    predicted: list = field(default_factory=list)   # [(x, y)] of the prediction
    local_count: int = 0                            # eq. 24
    predicted_speed: float = math.nan               # [m/s] at the end of the prediction
    cannot_follow: bool = False                     # the lane goal was set because of it
    temp_goal_y: float | None = None                # active temporary lane goal [m]
    active: int = 0                                 # obstacles within D_S


def local_count(points, y_now: float, lanes: Lanes) -> int:
    """Eq. 24: sum of sign(y_k - (y_nb + y_lc) / 2) over the predicted points.

    Oriented towards the nearest solid line y_nb (ours): +1 for a point between that
    middle line and the boundary, -1 for one on the lane-centre side; as printed, the
    count of a vehicle trapped against the right (lower) solid line would be negative.
    """
    y_lc = lanes.centre(lanes.lane_of(y_now))
    y_nb = lanes.nearest_boundary(y_now)
    mid = 0.5 * (y_nb + y_lc)
    toward = 1.0 if y_nb > y_lc else -1.0
    total = 0
    for _, y in points:
        s = (y - mid) * toward
        total += 1 if s > 0.0 else (-1 if s < 0.0 else 0)
    return total


def temporary_goal(y_now: float, lanes: Lanes) -> float:
    """Algorithm 1, Step 4: the centre of the lane next to the current one, away from y_nb.

    Printed ``Y_goal = y_lc - d_w sign(y - y_b)`` points off the road (towards the
    boundary); we take ``y_lc + d_w sign(y - y_b)``, clamped to the road's lanes.
    """
    lane = lanes.lane_of(y_now)
    away = 1 if y_now >= lanes.nearest_boundary(y_now) else -1
    return lanes.centre(min(max(lane + away, 0), lanes.count - 1))


class IAPFCore:
    """One IAPF planner (or the traditional baseline) with its temporary-goal memory."""

    def __init__(self, params: IAPFParams | None = None, use_numba: bool = True):
        self.p = params or IAPFParams()
        self.use_numba = use_numba and iapf_kernel.HAVE_NUMBA   # loads the kernel (numba) now
        self.temp_goal_y: float | None = None
        self.t_goal = -math.inf
        self._prm = None       # the kernel's params vector (packed once)

    def reset(self) -> None:
        """Forget the temporary lane goal and its timer (a new goal)."""
        self.temp_goal_y, self.t_goal = None, -math.inf

    # -- forces -------------------------------------------------------------------------
    def force(self, x: float, y: float, v: float, tracks, lanes: Lanes | None,
              y_goal: float | None, b3: float, shift: float = 0.0) -> tuple[float, float, float, int]:
        """``(F_X, F_Y, F_oX, active)``: eq. 13's resultant and the obstacles' X part, with the
        obstacles moved on at constant velocity for ``shift`` [s] (the fields depend on the
        host's position relative to each obstacle only, so the host is moved back instead)."""
        p = self.p
        half = p.goal_half_period_lanes * (lanes.width if lanes else 1.0)
        _, gx, gy = attraction_gradient(x, y, p.b1, p.b2, b3, y_goal, half)
        if lanes is not None:
            gy += road_gradient(y, lanes, p.k1, p.k2)[1]
        ox = oy = 0.0
        active = 0
        for ob in tracks:
            hx, hy = x - ob.vx * shift, y - ob.vy * shift
            if p.traditional:
                _, ux, uy = traditional_gradient(hx, hy, ob, p.k_trad)
            else:
                if gap(hx, hy, p.host_length, ob) >= safety_distance(v, ob.speed, p.a_b, p.s_m):
                    continue
                _, ux, uy = obstacle_gradient(hx, hy, ob, p.obstacle_gain, p.a_x, p.a_y,
                                              p.literal_rotation)
            active += 1
            ox -= ux
            oy -= uy
        return -gx + ox, -gy + oy, ox, active

    def advance(self, s: HostState, tracks, lanes: Lanes | None, y_goal: float | None, b3: float,
                dt: float, shift: float = 0.0) -> tuple[HostState, tuple]:
        """One move of ``dt``: velocity update (eqs. 25-26, with the stop law of
        :func:`stop_deceleration`), heading and position (21-22)."""
        p = self.p
        fx, fy, fox, active = self.force(s.x, s.y, s.v, tracks, lanes, y_goal, b3, shift)
        accel = 0.0
        v = s.v
        if not p.traditional:
            dv = p.v_cruise - v
            back = p.eta2 * dv * dv * dv
            if p.brake_priority and fox < 0.0:
                back = min(back, 0.0)
            accel = (p.eta1 * fox + back) / p.mass
            if p.stop_decel_frac > 0.0 and lanes is not None:
                need = stop_deceleration(s.x, s.y, v, tracks, lanes, p.host_length, p.s_m, shift)
                if need > p.stop_decel_frac * p.a_b:
                    accel = min(accel, -need)
            accel = min(max(accel, -p.a_b), p.a_max)
            v = min(max(v + accel * dt, 0.0), p.v_max_factor * p.v_cruise)
        lim = math.radians(p.heading_max_deg)
        yaw = min(max(math.atan2(fy, fx), -lim), lim)
        if p.yaw_rate_max_deg > 0.0:
            turn = math.radians(p.yaw_rate_max_deg) * dt
            yaw = min(max(yaw, s.yaw - turn), s.yaw + turn)
        return (HostState(s.x + math.cos(yaw) * v * dt, s.y + math.sin(yaw) * v * dt, v, yaw),
                (fx, fy, fox, accel, active))

    # -- Algorithm 1 --------------------------------------------------------------------
    def predict(self, s: HostState, tracks, lanes: Lanes, y_goal: float | None) -> np.ndarray:
        """Step 1: ``f_step`` states (x, y, v, yaw) ``predict_step_s`` apart, obstacles at
        constant velocity, the field without the temporary goal (the future the vehicle would
        drive into). Runs :func:`nodes.planner.iapf.kernels.rollout` (numba when available)."""
        p = self.p
        if self._prm is None:
            self._prm = iapf_kernel.pack_params(p)
        self._prm[iapf_kernel.HALF] = p.goal_half_period_lanes * lanes.width
        k = iapf_kernel
        return k.rollout((s.x, s.y, s.v, s.yaw), k.pack_obstacles(tracks), self._prm,
                       (lanes.y_min, lanes.width, lanes.count), y_goal, p.b3, p.predict_step_s,
                       p.f_step, self.use_numba)

    def lane_free(self, y_lane: float, s: HostState, tracks, lanes: Lanes) -> bool:
        """No vehicle in the lane centred at ``y_lane`` beside the host or ahead within the
        safety distance at the cruise speed, and none behind closing in within its own (ours:
        the "decision module" the paper assumes)."""
        p = self.p
        for ob in tracks:
            if abs(ob.y - y_lane) >= 0.5 * lanes.width:
                continue
            g = gap(s.x, s.y, p.host_length, ob)
            if ob.x > s.x - 0.5 * (p.host_length + ob.length):      # beside or ahead
                if g < safety_distance(p.v_cruise, ob.speed, p.a_b, p.s_m):
                    return False
            elif ob.vx > s.v and g < safety_distance(ob.speed, s.v, p.a_b, p.s_m):
                return False                                         # closing from behind
        return True

    def _cannot_follow(self, s: HostState, tracks, lanes: Lanes) -> bool:
        """A vehicle ahead in the host's lane, within D_S at the cruise speed, slower than
        ``follow_min_frac`` V_c,
        and the next lane free (ours, Sec. 2.1: "if the obstacle vehicle has a much lower speed
        than the host vehicle, the host will have to perform lane-changing maneuvers")."""
        p = self.p
        if p.follow_min_frac <= 0.0:
            return False
        lane = lanes.lane_of(s.y)
        slow = any(lanes.lane_of(ob.y) == lane and ob.x > s.x and ob.speed < p.follow_min_frac *
                   p.v_cruise and gap(s.x, s.y, p.host_length, ob) < safety_distance(
                       p.v_cruise, ob.speed, p.a_b, p.s_m) for ob in tracks)
        return slow and self.lane_free(temporary_goal(s.y, lanes), s, tracks, lanes)

    def lane_goal(self, s: HostState, tracks, lanes: Lanes | None, y_goal: float | None,
                  goal_x: float | None) -> tuple[float | None, float]:
        """(Y_goal, b3) of the permanent lane goal: Table 1's b3, or ``b3_temp`` within
        ``goal_lane_s`` of cruising from the goal when the goal's lane is free (ours: the host
        must be near the goal lane's centre to reach a goal point)."""
        p = self.p
        if (y_goal is None or goal_x is None or lanes is None or p.goal_lane_s <= 0.0
                or goal_x - s.x > p.goal_lane_s * p.v_cruise
                or not self.lane_free(y_goal, s, tracks, lanes)):
            return y_goal, p.b3
        return y_goal, p.b3_temp

    def step(self, s: HostState, tracks, lanes: Lanes | None, t: float,
             y_goal: float | None = None, dt: float | None = None,
             goal_x: float | None = None) -> tuple[HostState, StepInfo]:
        """One planning step at time ``t`` [s] of ``dt`` (default ``step_s``); ``y_goal``,
        ``goal_x``: the goal's lane centre and x [m] (None: cruise along the road)."""
        p = self.p
        dt = p.step_s if dt is None else dt
        info = StepInfo()
        if lanes is not None:
            tracks = road_headings(tracks, p.heading_min_speed)
        if self.temp_goal_y is not None and t >= self.t_goal + p.t_c:      # Step 6
            self.temp_goal_y = None
        if p.prediction and not p.traditional and lanes is not None:
            future = self.predict(s, tracks, lanes, y_goal)
            info.predicted = [tuple(r) for r in future[:, :2].tolist()]
            info.predicted_speed = float(future[-1, 2])
            info.local_count = local_count(info.predicted, s.y, lanes)      # Step 2
            info.cannot_follow = self._cannot_follow(s, tracks, lanes)
            if info.local_count > p.c_f or info.cannot_follow:              # Step 3
                self.temp_goal_y, self.t_goal = temporary_goal(s.y, lanes), t  # Step 4
        goal_y, b3 = self.lane_goal(s, tracks, lanes, y_goal, goal_x)
        if self.temp_goal_y is not None:                                    # Step 5
            goal_y, b3 = self.temp_goal_y, p.b3_temp
        new, (fx, fy, fox, accel, active) = self.advance(s, tracks, lanes, goal_y, b3, dt)
        info.force, info.f_ox, info.accel, info.active = (fx, fy), fox, accel, active
        info.temp_goal_y = self.temp_goal_y
        return new, info
