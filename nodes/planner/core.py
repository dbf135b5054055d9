"""The planner core: scan + odometry -> velocity command (pure; no zenoh).

:class:`Planner` owns what every algorithm shares (scan points, goal, the motion law of
PAPF eqs. 3 and 5, goal reached, stagnation, messages); the algorithm is a
:class:`Strategy` found by name in :mod:`nodes.planner.registry`. Used by the planner
node's loop (:mod:`nodes.planner.loop`) and the offline simulations (papf/offline/).
"""

from __future__ import annotations

import dataclasses
import functools
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from common.robot import GOAL_TOLERANCE_MIN_M
from common.units import NS_PER_S
from nodes.planner.debug import DebugField, check_declarations, debug_values
from nodes.planner.field import APFParams, heading_ref, speed_ref, turn_rate, wrap_angle
from nodes.planner.road import Lanes, Track
from nodes.planner.rollout import rollout, stop_plan
from nodes.planner.scan_kernel import scan_points
from nodes.planner.stagnation import StagnationWatch
from schemas.messages import Goal, Objects, Odometry, PlannerState, PlannerStatus, Scan, Twist


@dataclass(frozen=True)
class ScanView:
    """One scan in the world frame. ``ranges`` keeps every beam (invalid ones = inf) in scan order."""

    origin: np.ndarray      # (2,) sensor position, world frame [m]
    angles: np.ndarray      # (B,) world-frame direction of each beam [rad]
    ranges: np.ndarray      # (B,) [m], inf where nan/inf/outside [range_min, range_max]
    points: np.ndarray      # (K, 2) world-frame points of the valid beams, scan order [m]
    valid: np.ndarray       # (B,) bool


def scan_view(scan: Scan, odom: Odometry, use_numba: bool = True) -> ScanView:
    """Beams -> world frame using the robot pose and the sensor offset; drop invalid returns.

    A return is valid when finite and within [range_min, range_max]. ``use_numba``: the
    compiled loop (if numba is installed) or numpy; the same values bit for bit.
    """
    c, s = math.cos(odom.yaw), math.sin(odom.yaw)
    origin = np.array([odom.x + c * scan.sensor_x - s * scan.sensor_y,
                       odom.y + s * scan.sensor_x + c * scan.sensor_y])
    ranges = np.asarray(scan.ranges, dtype=float)
    angles = odom.yaw + scan.sensor_yaw + scan.angle_min + _beam_offsets(
        scan.angle_increment, ranges.size, math.copysign(1.0, scan.angle_increment))
    # numpy's cos/sin of every beam (elementwise: the same values as of the valid ones alone)
    ranges, points, valid = scan_points(ranges, np.cos(angles), np.sin(angles), scan.range_min,
                                        scan.range_max, origin, use_numba)
    return ScanView(origin, angles, ranges, points, valid)


@functools.lru_cache(maxsize=8)
def _beam_offsets(increment: float, beams: int, _sign: float) -> np.ndarray:
    """``increment * arange(beams)`` (read-only; the same few scan layouts every cycle;
    ``_sign`` keeps -0.0 and 0.0 apart in the cache)."""
    out = increment * np.arange(beams)
    out.flags.writeable = False
    return out


@dataclass
class Plan:
    """A strategy's answer: the force to steer by and what to show (world frame, 2-D).

    The named fields are what every planner has; a plug-in's own output goes in ``debug``
    (name -> value of a field its ``DEBUG`` declares: :mod:`nodes.planner.debug`).
    """

    force: np.ndarray
    mode: str = "drive"
    temporary_goal: tuple = ()
    predicted_path: np.ndarray | tuple = ()
    debug: dict = field(default_factory=dict)   # the plug-in's declared fields -> this cycle's values
    stagnated: str = ""     # non-empty: the strategy declares stagnation, with this reason
    searching: bool = False  # the strategy found something new this cycle (e.g. placed a top quark)
    heading: float | None = None  # [rad] the strategy's own heading reference (e.g. IAPF eq. 21)
    v_ref: float | None = None    # [m/s] the strategy's own speed instead of eq. 5 (e.g. IAPF eq. 26)
    obstacles_used: int | None = None   # obstacles that shaped the field; None: the scan's points


@dataclass(frozen=True)
class NoParams:
    """A strategy with no settings beyond :class:`~nodes.planner.field.APFParams`."""


class Strategy:
    """An algorithm on the shared APF core: every hook and declaration, with its default.

    A planner plug-in (``nodes/planner/<name>/``) subclasses this, sets ``name`` and
    overrides :meth:`plan`; everything else is optional. The declarations below are what
    the rest of the house derives from (CLI choices, colours, experiments' planner lists,
    which runs need obstacle tracks, ...): see :mod:`nodes.planner.registry`.
    """

    name: ClassVar[str] = ""                 # the ``--planner`` name
    rank: ClassVar[int] = 100                # order in lists (CLI, experiments' rows)
    Params: ClassVar[type] = NoParams        # frozen dataclass of the algorithm's own settings
    SPECS: ClassVar[dict] = {}               # Params field -> common.params.Spec (type, range)
    PAPER_PRESET: ClassVar[dict] = {}        # ``--preset paper``: the paper read literally
    roles: ClassVar[tuple[str, ...]] = ()    # parts it plays in comparisons (registry.ROLES)
    colour: ClassVar[str] = ""               # matplotlib colour of its paths ("" = by index)
    colour_map: ClassVar[str] = ""           # matplotlib colour map in report figures
    uses_objects: ClassVar[bool] = False     # reads obstacle tracks (``observe``)
    planar_only: ClassVar[bool] = False      # reads the planar scan's beams, not just points
    car_variants: ClassVar[dict] = {}        # car-scale name -> (label, Params changes, colour)
    uses_numba: bool = False                 # runs numba kernels (the scan view compiles too)
    DEBUG: ClassVar[tuple[DebugField, ...]] = ()   # its own debug output (nodes/planner/debug.py)

    def __init__(self, params=None):
        self.params = params if params is not None else self.Params()

    def reset(self) -> None:
        """Forget per-goal memory (called on a new goal)."""

    def observe(self, objects: tuple, road: Lanes | None, t: float, v: float) -> None:
        """The cycle's obstacle tracks, the road, time [s] and speed [m/s], before :meth:`plan`."""

    def warm_up(self, apf: APFParams) -> None:
        """Compile kernels before the node declares itself ready (none by default)."""

    @classmethod
    def check_strength(cls, apf: APFParams, params) -> None:
        """ConfigError unless its own repulsion products are above their measured floors
        (beyond each setting's range; none by default: docs/planners.md "Safety floors")."""

    def plan(self, pos: np.ndarray, yaw: float, goal: np.ndarray, view: ScanView,
             apf: APFParams) -> Plan:
        """The force at ``pos`` [m] (world frame) and the debug geometry."""
        raise NotImplementedError(f"{type(self).__name__}.plan")


def _points(a) -> tuple:
    """(K, >=2) array-like -> tuple of (x, y) Python floats (the first two coordinates)."""
    arr = np.asarray(a, dtype=float)
    if arr.size == 0:
        return ()
    return tuple(map(tuple, arr.reshape(arr.shape[0] if arr.ndim > 1 else 1, -1)[:, :2].tolist()))


def _norm(v) -> float:
    """``np.linalg.norm(v)`` of a vector, without its checks (the same ``sqrt(v . v)``)."""
    a = np.asarray(v, dtype=float).ravel()
    return math.sqrt(a.dot(a))


class Planner:
    """Goal, motion law, status and messages around one :class:`Strategy`.

    What the run tells the planner beyond scan and odometry: the **road** comes with the
    goal (:attr:`road`, from the ``Goal`` message's ``road_*`` fields — the planner never
    reads a world file) and the **obstacle tracks** of the cycle come as an optional
    ``Objects`` message paired with the scan (:meth:`step`), kept as :attr:`objects`;
    :meth:`Strategy.observe` receives them before each ``plan``.

    Deterministic: outputs depend only on the inputs (``compute_ns`` excepted).
    """

    def __init__(self, strategy: Strategy, apf: APFParams | None = None):
        check_declarations(strategy.name, strategy.DEBUG)
        self.strategy = strategy
        # the scan view compiled only where the strategy runs numba anyway (PAPF, IAPF): a
        # planner without kernels never imports numba (nodes/planner/lazy.py); same values
        self.jit_scan = bool(strategy.uses_numba)
        self.apf = apf or APFParams()
        self.goal: Goal | None = None
        self.state = "idle"
        self.reason = ""
        self.watch = StagnationWatch()  # no progress towards the goal -> stagnated
        self._apf_for_l: dict[int, APFParams] = {}
        self.objects: tuple = ()        # latest obstacle tracks (strategies that use them)
        self.road = None                # the road of the run, once announced
        # the short plan each command carries on a real link (nodes/planner/rollout.py);
        # 0 steps (lockstep, offline) = plain commands, as before
        self.plan_steps = 0
        self.plan_dt_ns = 100_000_000
        self.passing = None             # nodes.planner.passing.Passing in a fleet, else None

    # -- inputs beyond scan and odometry -------------------------------------
    def set_objects(self, tracks) -> None:
        """The latest obstacle tracks (:class:`nodes.planner.road.Track`)."""
        self.objects = tuple(tracks)

    def set_road(self, road: Lanes | None) -> None:
        """The road of the run, or None (normally it comes with the goal, :meth:`set_goal`)."""
        self.road = road

    # -- goal ---------------------------------------------------------------
    def set_goal(self, goal: Goal) -> PlannerStatus:
        """Take a goal; the same goal again keeps the run going. Returns the ``ready`` status
        (``idle`` for a cancelling goal: no goal, zero commands until the next one)."""
        if goal.cancel:
            self.goal, self.state, self.reason = None, "idle", "goal canceled"
            self.strategy.reset()
            return PlannerStatus(stamp_ns=goal.stamp_ns, state="idle", reason=self.reason)
        same = self.goal is not None and (self.goal.x, self.goal.y, self.goal.tolerance) == (
            goal.x, goal.y, goal.tolerance)
        # the goal handshake carries the run's road (none: road_lanes = 0)
        self.road = (Lanes(goal.road_y_min, goal.road_lane_width, goal.road_lanes)
                     if goal.road_lanes > 0 and goal.road_lane_width > 0 else None)
        if not same:
            self.goal = goal
            self.state, self.reason = "ready", ""
            self.watch.reset()
            self.strategy.reset()
        return PlannerStatus(stamp_ns=goal.stamp_ns, state="ready", reason=self.reason)

    def set_params(self, apf: APFParams, algo) -> None:
        """New settings from the next cycle on (the stagnation watch and strategy memory stay)."""
        self.apf = apf
        self._apf_for_l.clear()
        self.strategy.params = algo

    # -- one cycle ----------------------------------------------------------
    def step(self, scan: Scan, odom: Odometry, objects: Objects | None = None
             ) -> tuple[Twist, PlannerState, PlannerStatus]:
        """One control cycle for ``scan`` (the command carries the scan's stamp).

        ``objects``: the obstacle tracks paired with this scan, if the run provides them
        (None: keep the last ones).
        """
        cmd, finish = self.command(scan, odom, objects)
        return (cmd, *finish())

    def command(self, scan: Scan, odom: Odometry, objects: Objects | None = None
                ) -> tuple[Twist, Callable[[], tuple]]:
        """The cycle's command now; ``finish()`` -> ``(PlannerState, PlannerStatus)`` after.

        The node publishes the command before it builds the debug message (tens of
        microseconds with PAPF's abandoned paths): the command's latency is the
        algorithm's alone. ``compute_ns`` is the time to the command. ``finish(False)``
        skips the debug message (None in its place) when nobody listens to it.
        """
        if objects is not None:
            self.set_objects(Track(o.x, o.y, o.yaw, o.vx, o.vy, o.length, o.width, o.id)
                             for o in objects.tracks)
        t0 = time.perf_counter_ns()
        t = scan.stamp_ns
        if self.goal is None:
            return self._stop(t, "idle", "no goal", math.nan, t0, odom=odom)
        pos = np.array([odom.x, odom.y])
        goal = np.array([self.goal.x, self.goal.y])
        dist = float(np.hypot(self.goal.x - odom.x, self.goal.y - odom.y))
        if self.state in ("reached", "stagnated", "failed"):
            return self._stop(t, self.state, self.reason, dist, t0, odom=odom)
        tolerance = max(self.goal.tolerance, GOAL_TOLERANCE_MIN_M)   # a peer's 0 is never reached
        if dist <= tolerance:
            return self._stop(t, "reached", f"within {tolerance} m of the goal", dist, t0,
                              odom=odom)
        apf = self._params_for(len(scan.ranges))
        view = scan_view(scan, odom, self.jit_scan)
        self.strategy.observe(self.objects, self.road, t / NS_PER_S, odom.v)
        plan = self.strategy.plan(pos, odom.yaw, goal, view, apf)
        why = plan.stagnated or self.watch.check(t, dist, apf, pos, plan.searching)
        if why:
            return self._stop(t, "stagnated", why, dist, t0, plan, view, odom)
        theta_ref = heading_ref(plan.force) if plan.heading is None else plan.heading
        err = wrap_angle(theta_ref - odom.yaw)
        if plan.v_ref is None:
            v = speed_ref(_norm(plan.force), err, apf)
        else:  # the planned velocity's component along the robot's heading (ours)
            v = max(0.0, plan.v_ref * math.cos(err))
        w = turn_rate(theta_ref, odom.yaw, apf)
        if self.passing is not None and self.objects:   # a fleet: robots that pass each other
            v_des = speed_ref(_norm(plan.force), 0.0, apf) if plan.v_ref is None else plan.v_ref
            v, w = self.passing.adjust(odom.x, odom.y, odom.yaw, odom.v, theta_ref, v_des, v, w,
                                       self.objects, apf)
        self.state, self.reason = "driving", ""
        compute_ns = time.perf_counter_ns() - t0
        return self._twist(t, v, w, odom, theta_ref, plan, apf), lambda debug=True: (
            self._state(t, plan, view, theta_ref, v, w, compute_ns) if debug else None,
            PlannerStatus(stamp_ns=t, state="driving", distance_to_goal=dist))

    def warm_up(self) -> None:
        """Compile the JIT kernels (the scan view; the strategy's ``warm_up(apf)`` if any)."""
        scan_view(Scan(stamp_ns=0, angle_min=0.0, angle_increment=0.5, range_min=0.1,
                       range_max=5.0, ranges=np.array([1.0, np.inf, 2.0], np.float32)),
                  Odometry(stamp_ns=0, x=0.0, y=0.0, yaw=0.0, v=0.0, w=0.0), self.jit_scan)
        self.strategy.warm_up(self.apf)

    # -- helpers ------------------------------------------------------------
    def _params_for(self, beams: int) -> APFParams:
        if not self.apf.scale_to_scan or beams == 0 or beams == self.apf.lidar_points:
            return self.apf
        if beams not in self._apf_for_l:
            if len(self._apf_for_l) >= 16:   # scans of ever new lengths (a peer's): bounded
                self._apf_for_l.clear()
            self._apf_for_l[beams] = dataclasses.replace(self.apf, lidar_points=beams)
        return self._apf_for_l[beams]

    def _twist(self, t: int, v: float, w: float, odom: Odometry | None, theta_ref: float = 0.0,
               plan: Plan | None = None, apf: APFParams | None = None) -> Twist:
        """The cycle's command, with its short plan when :attr:`plan_steps` asks for one."""
        if self.plan_steps <= 0 or odom is None:
            return Twist(stamp_ns=t, v=v, w=w)
        if plan is None:
            poses = stop_plan(odom.x, odom.y, odom.yaw, self.plan_steps)
        else:
            norm = _norm(plan.force)
            speed = ((lambda err: speed_ref(norm, err, apf)) if plan.v_ref is None else
                     (lambda err, vr=plan.v_ref: max(0.0, vr * math.cos(err))))
            poses = rollout(odom.x, odom.y, odom.yaw, theta_ref, speed, apf,
                            self.plan_dt_ns / NS_PER_S, self.plan_steps)
        return Twist(stamp_ns=t, v=v, w=w, plan=poses, plan_dt_ns=self.plan_dt_ns)

    def _stop(self, t, state, reason, dist, t0, plan: Plan | None = None,
              view: ScanView | None = None, odom: Odometry | None = None):
        if state != "idle":
            self.state, self.reason = state, reason
        plan = plan or Plan(force=np.zeros(2), mode="stop")
        plan.mode = "stop" if state != "idle" else "idle"
        compute_ns = time.perf_counter_ns() - t0
        return self._twist(t, 0.0, 0.0, odom), lambda debug=True: (
            self._state(t, plan, view, 0.0, 0.0, 0.0, compute_ns) if debug else None,
            PlannerStatus(stamp_ns=t, state=state, reason=reason, distance_to_goal=dist))

    def _state(self, t, plan: Plan, view, theta_ref, v, w, compute_ns: int) -> PlannerState:
        force = np.asarray(plan.force, dtype=float)
        strategy = self.strategy
        used = (plan.obstacles_used if plan.obstacles_used is not None else
                0 if view is None else view.points.shape[0])
        # every value below is already in the message's own form (Python floats, tuples):
        # from_normal skips the constructor's second pass over the paths
        return PlannerState.from_normal(
            stamp_ns=int(t), algorithm=strategy.name, mode=str(plan.mode),
            force=(float(force[0]), float(force[1])), heading_ref=float(theta_ref),
            v_ref=float(v), w_ref=float(w),
            temporary_goal=tuple(float(x) for x in plan.temporary_goal),
            predicted_path=_points(plan.predicted_path), obstacle_count=int(used),
            v_target=float(plan.v_ref) if plan.v_ref is not None else float(v),
            compute_ns=compute_ns,
            debug=debug_values(strategy.name, strategy.DEBUG, plan.debug))
