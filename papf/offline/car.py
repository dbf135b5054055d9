"""Offline road runs with the IAPF paper's vehicle model (Jin 2024, eqs. 21-22, step 0.02 s).

The host is the planner's own particle: every ``step_s`` the IAPF (or traditional APF)
step moves it along the force at the updated speed; the other vehicles follow their
world tracks exactly and are seen as ground-truth tracks (pose, velocity, size). Each
step checks the host's footprint (a rectangle along its heading) against every vehicle's
footprint, and the footprint against the road's solid lines.

:func:`run_road` -> :class:`RoadRun` (time series + summary figures).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from nodes.planner.iapf.algorithm import HostState, IAPFCore
from nodes.planner.road import Lanes, Track
from worlds.shapes import rect_corners

Mover = Callable[[float], Track]   # sim time [s] -> the vehicle's track at that time


def _seg_point_dist(a: np.ndarray, b: np.ndarray, pts: np.ndarray) -> np.ndarray:
    ab = b - a
    t = np.clip(((pts - a) @ ab) / max(float(ab @ ab), 1e-18), 0.0, 1.0)
    return np.linalg.norm(pts - (a + t[:, None] * ab), axis=1)


def _overlap(p: np.ndarray, q: np.ndarray) -> bool:
    """Separating-axis test of two convex quadrilaterals."""
    for poly in (p, q):
        for i in range(4):
            edge = poly[(i + 1) % 4] - poly[i]
            axis = np.array([-edge[1], edge[0]])
            a, b = p @ axis, q @ axis
            if a.max() < b.min() or b.max() < a.min():
                return False
    return True


def rect_clearance(p: np.ndarray, q: np.ndarray) -> float:
    """Distance between two rectangles' outlines [m]; negative (-1e-3) when they overlap."""
    if _overlap(p, q):
        return -1e-3
    best = math.inf
    for poly, other in ((p, q), (q, p)):
        for i in range(4):
            best = min(best, float(_seg_point_dist(poly[i], poly[(i + 1) % 4], other).min()))
    return best


@dataclass
class RoadRun:
    """One run: per step time [s], x, y [m], v [m/s], yaw [rad], plus what the planner did."""

    planner: str
    outcome: str                    # reached (passed the finish line) | collision | timeout
    times: np.ndarray
    states: np.ndarray              # (N, 4) x, y, v, yaw
    temp_goal: np.ndarray           # (N,) y of the active temporary goal, nan when none
    local_counts: np.ndarray        # (N,) eq. 24 count of each step
    step_us: np.ndarray             # (N-1,) wall time of each planning step [us]
    step_cpu_us: np.ndarray         # (N-1,) thread CPU time of each planning step [us]
    min_clearance_m: float
    collisions: int                 # contact episodes (a vehicle touching the host, once each)
    left_road: bool
    lane_changes: int
    others: list = field(default_factory=list)   # per vehicle (N, 3) x, y, yaw

    def summary(self) -> dict:
        v = self.states[:, 2]
        return {"collisions": self.collisions, "min_clearance_m": round(self.min_clearance_m, 4),
                "left_road": self.left_road, "lane_changes": self.lane_changes,
                "min_speed_mps": round(float(v.min()), 4), "max_speed_mps": round(float(v.max()), 4)}


def lane_changes(ys: Sequence[float], lanes: Lanes) -> int:
    """Times the host's centre crossed a broken line (its lane index changed)."""
    idx = [lanes.lane_of(y) for y in ys]
    return sum(1 for a, b in zip(idx[:-1], idx[1:], strict=True) if a != b)


def outside_road(corners: np.ndarray, lanes: Lanes) -> bool:
    """True when any footprint corner is beyond a solid line."""
    return bool((corners[:, 1] < lanes.y_min).any() or (corners[:, 1] > lanes.y_max).any())


class _Contacts:
    """Clearance and contact episodes of the host against every vehicle."""

    def __init__(self, n: int):
        self.min_clear, self.episodes = math.inf, 0
        self.touching = [False] * n

    def check(self, host: np.ndarray, tracks) -> bool:
        hit = False
        for i, ob in enumerate(tracks):
            c = rect_clearance(host, rect_corners(ob.x, ob.y, ob.yaw, ob.length, ob.width))
            self.min_clear = min(self.min_clear, c)
            now = c < 0.0
            self.episodes += now and not self.touching[i]
            self.touching[i] = now
            hit |= now
        return hit


def run_road(core: IAPFCore, start: HostState, movers: Sequence[Mover], lanes: Lanes,
             duration_s: float, name: str, y_goal: float | None = None,
             finish_x: float | None = None, stop_on_collision: bool = False,
             goal_x: float | None = None) -> RoadRun:
    """Run ``core`` from ``start`` among ``movers`` for ``duration_s`` of sim time, or until the
    host passes ``finish_x`` (outcome ``reached``) or, with ``stop_on_collision``, touches a
    vehicle (``collision``)."""
    p = core.p
    core.reset()
    n = int(round(duration_s / p.step_s))
    s = start
    rows, temp, counts, times_us, cpu_us = [(0.0, s.x, s.y, s.v, s.yaw)], [math.nan], [0], [], []
    others = [[] for _ in movers]
    contacts, left, outcome = _Contacts(len(movers)), False, "timeout"
    for k in range(n + 1):
        t = k * p.step_s
        tracks = [m(t) for m in movers]
        for i, ob in enumerate(tracks):
            others[i].append((ob.x, ob.y, ob.yaw))
        host = rect_corners(s.x, s.y, s.yaw, p.host_length, p.host_width)
        hit = contacts.check(host, tracks)
        left |= outside_road(host, lanes)
        if hit and stop_on_collision:
            outcome = "collision"
            break
        if finish_x is not None and s.x >= finish_x:
            outcome = "reached"
            break
        if k == n:
            break
        t0, c0 = time.perf_counter_ns(), time.thread_time_ns()
        s, info = core.step(s, tracks, lanes, t, y_goal, goal_x=goal_x)
        cpu_us.append((time.thread_time_ns() - c0) / 1e3)
        times_us.append((time.perf_counter_ns() - t0) / 1e3)
        rows.append((t + p.step_s, s.x, s.y, s.v, s.yaw))
        temp.append(math.nan if info.temp_goal_y is None else info.temp_goal_y)
        counts.append(info.local_count)
    arr = np.array(rows)
    return RoadRun(planner=name, outcome=outcome, times=arr[:, 0], states=arr[:, 1:],
                   temp_goal=np.array(temp), local_counts=np.array(counts),
                   step_us=np.array(times_us), step_cpu_us=np.array(cpu_us), min_clearance_m=float(contacts.min_clear),
                   collisions=contacts.episodes, left_road=left,
                   lane_changes=lane_changes(arr[:, 2], lanes),
                   others=[np.array(o) for o in others])


def road_figures(lanes: Lanes, times: np.ndarray, path: np.ndarray, headings: np.ndarray,
                 size: tuple[float, float]) -> dict:
    """``left_road``, ``lane_changes``, ``min_speed_mps``, ``max_speed_mps`` of a path on a road
    (footprint ``size`` = (length, width) [m] along the heading; speeds from the path)."""
    left = any(outside_road(rect_corners(x, y, h, *size), lanes)
               for (x, y), h in zip(path, headings, strict=True))
    v = np.zeros(1)
    if path.shape[0] > 1:
        dt = np.diff(times)
        ok = dt > 0
        if ok.any():
            v = np.linalg.norm(np.diff(path, axis=0), axis=1)[ok] / dt[ok]
    return {"left_road": bool(left), "lane_changes": lane_changes(path[:, 1], lanes),
            "min_speed_mps": round(float(v.min()), 4), "max_speed_mps": round(float(v.max()), 4)}
