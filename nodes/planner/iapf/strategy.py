"""IAPF as a planner strategy (``--planner iapf``): :class:`~nodes.planner.iapf.algorithm.IAPFCore`
on the obstacle tracks and the road the run announced, scaled to the ROSbot.

It reads tracks, not the scan (``observe``), and outputs a heading (eq. 21) and a speed
(eq. 26) that the planner core tracks. Inputs and scale: docs/planners.md, "The algorithms
in the code" and its IAPF section.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from common.robot import BODY_LENGTH_M, BODY_WIDTH_M
from nodes.planner import lazy
from nodes.planner.core import Plan, ScanView, Strategy
from nodes.planner.debug import DebugField, Style
from nodes.planner.field import APFParams
from nodes.planner.iapf.algorithm import PAPER_PRESET, HostState, IAPFCore, IAPFParams, scaled
from nodes.planner.iapf.settings import IAPF
from nodes.planner.road import Lanes, Track

LANE_GOAL_AHEAD = 1.0  # [s] the temporary lane goal is drawn this far ahead at the cruise speed


class IAPFStrategy(Strategy):
    """Jin 2024 IAPF on the shared planner core."""

    name = "iapf"
    rank = 5
    roles = ("car-proposed",)
    colour_map = "Reds"
    uses_objects = True   # its fields are built from tracked vehicles (Sec. 2.2.3)
    #: the offline car-scale runs (papf/offline/road.py): name -> (label, settings changed,
    #: colour); the first is IAPF itself, the paper's Table 2 rows are these names
    car_variants = {"iapf": ("IAPF", {}, "tab:blue"),
                    "iapf-np": ("IAPF without prediction", {"prediction": False}, "tab:green"),
                    "apf": ("traditional APF", {"traditional": True, "prediction": False}, "tab:red")}
    Params = IAPFParams
    SPECS = IAPF
    PAPER_PRESET = PAPER_PRESET
    DEBUG = (
        DebugField("local_minimum_count", "count", label="local minima ahead",
                   doc="eq. 24: signed count of the predicted points near the solid line"),
        DebugField("lane_goal_y", "scalar", unit="m", label="lane goal y",
                   doc="the temporary lane goal (Steps 4-6); nan when none",
                   style=Style((0.09, 0.75, 0.81, 1.0))),
    )

    def __init__(self, params: IAPFParams | None = None):
        self.params = params or IAPFParams()
        self.uses_numba = lazy.HAVE_NUMBA   # its rollout kernel; the scan view compiled too
        self.tracks: tuple[Track, ...] = ()
        self.lanes: Lanes | None = None
        self.t_s = 0.0
        self.v_odom = 0.0
        self._core: IAPFCore | None = None
        self._core_for: Lanes | None = None
        self.v: float | None = None

    def reset(self) -> None:
        """Forget the core's lane goal and the planned speed (a new goal)."""
        if self._core is not None:
            self._core.reset()
        self.v = None

    def warm_up(self, apf: APFParams) -> None:
        """Compile the prediction kernel (numba) before the node declares itself ready."""
        core = IAPFCore(self.params)
        core.predict(HostState(0.0, 0.0, 1.0), [Track(5.0, 0.0, 0.0, 1.0, 0.0, 4.5, 1.8)],
                     Lanes(-2.0, 4.0, 2), 0.0)

    def observe(self, tracks, lanes: Lanes | None, t_s: float, v_odom: float) -> None:
        """The latest obstacle tracks, the road (None: not known yet), sim time [s], speed."""
        self.tracks = tuple(tracks)
        self.lanes = lanes
        self.t_s, self.v_odom = t_s, v_odom

    def core_for(self, lanes: Lanes) -> IAPFCore:
        """The core with parameters scaled to this road (kept while the road is the same)."""
        if self._core is None or self._core_for != lanes:
            p = self.params
            s = lanes.width / p.lane_width_ref
            tau = s * p.v_cruise / p.cruise_speed
            # the robot's heading controller limits its turn rate: no particle rate limit on top
            # and the safety gaps are measured from the robot's own footprint
            # the robot must be able to stop behind a vehicle: an obstacle pushing back
            # suspends the return to cruise (eq. 25's cubic beats any braking force otherwise)
            # and it must stop S_m short of a standing vehicle in its lane (the stop law)
            q = dataclasses.replace(scaled(p, s, tau), yaw_rate_max_deg=0.0, brake_priority=True,
                                    host_length=BODY_LENGTH_M, host_width=BODY_WIDTH_M,
                                    stop_decel_frac=p.node_stop_decel_frac)
            self._core, self._core_for = IAPFCore(q), lanes
        return self._core

    def plan(self, pos: np.ndarray, yaw: float, goal: np.ndarray, view: ScanView,
             apf: APFParams) -> Plan:
        """One IAPF step on the observed tracks and road: heading [rad] (eq. 21) and speed [m/s] (eq. 26)."""
        if self.lanes is None:
            return Plan(force=np.zeros(2), mode="no-road", v_ref=0.0, heading=yaw,
                        obstacles_used=0)
        core = self.core_for(self.lanes)
        if self.v is None:   # the planned speed starts at the robot's own
            self.v = max(0.0, self.v_odom)
        state = HostState(float(pos[0]), float(pos[1]), self.v, yaw)
        y_goal = self.lanes.centre(self.lanes.lane_of(float(goal[1])))
        new, info = core.step(state, self.tracks, self.lanes, self.t_s, y_goal,
                              goal_x=float(goal[0]))
        self.v = new.v
        temp = ()
        if info.temp_goal_y is not None:
            temp = (state.x + LANE_GOAL_AHEAD * core.p.v_cruise, info.temp_goal_y)
        return Plan(force=np.array(info.force), mode="lane-goal" if temp else "drive",
                    temporary_goal=temp, predicted_path=np.array(info.predicted).reshape(-1, 2),
                    heading=new.yaw, v_ref=new.v, obstacles_used=info.active,
                    debug={"local_minimum_count": info.local_count,
                           "lane_goal_y": math.nan if info.temp_goal_y is None else info.temp_goal_y})
