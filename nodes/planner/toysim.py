"""A tiny kinematic 2-D world for planner tests and benchmarks (no physics, no zenoh).

- :func:`cast_scan`: a 360-degree scan of circles and line segments from a pose (exact ray
  intersection, vectorised over beams), as a :class:`~schemas.messages.Scan`.
- :func:`simulate`: run a :class:`~nodes.planner.core.Planner` in closed loop with an ideal
  unicycle (commands held for one scan period, integrated exactly); returns the path and
  the last status. Odometry = ground truth, no noise: a reproducible stand-in for the stack.

Not the simulator of the stack (that is nodes/base_driver + nodes/lidar_sim, pybullet).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from schemas.messages import Goal, Odometry, Scan

SCAN_PERIOD_NS = 100_000_000  # [ns] 10 Hz, as docs/architecture.md
RANGE_MIN_M, RANGE_MAX_M = 0.2, 25.0  # RPLIDAR A3 (DESIGN.md §5)


@dataclass(frozen=True)
class ToyWorld:
    """Circles ``(x, y, radius)`` and segments ``(x0, y0, x1, y1)`` [m]."""

    circles: tuple[tuple[float, float, float], ...] = ()
    segments: tuple[tuple[float, float, float, float], ...] = ()

    def clearance(self, x: float, y: float) -> float:
        """Distance from (x, y) to the nearest obstacle surface [m] (inf if none)."""
        best = math.inf
        for cx, cy, r in self.circles:
            best = min(best, math.hypot(x - cx, y - cy) - r)
        for x0, y0, x1, y1 in self.segments:
            d = np.array([x1 - x0, y1 - y0])
            u = np.clip(np.dot([x - x0, y - y0], d) / max(np.dot(d, d), 1e-12), 0.0, 1.0)
            best = min(best, math.hypot(x - x0 - u * d[0], y - y0 - u * d[1]))
        return best


def box_segments(cx: float, cy: float, sx: float, sy: float) -> tuple:
    """The 4 sides of an axis-aligned box as segments."""
    x0, x1, y0, y1 = cx - sx / 2, cx + sx / 2, cy - sy / 2, cy + sy / 2
    return ((x0, y0, x1, y0), (x1, y0, x1, y1), (x1, y1, x0, y1), (x0, y1, x0, y0))


def cast_scan(world: ToyWorld, x: float, y: float, yaw: float, stamp_ns: int = 0,
              beams: int = 300, range_max: float = RANGE_MAX_M) -> Scan:
    """Ranges of ``beams`` rays over 360 degrees from (x, y, yaw); inf = no return."""
    inc = 2.0 * math.pi / beams
    ang = yaw + (-math.pi + inc * np.arange(beams))
    dx, dy = np.cos(ang), np.sin(ang)
    best = np.full(beams, np.inf)
    for cx, cy, r in world.circles:
        ox, oy = x - cx, y - cy
        b = ox * dx + oy * dy
        disc = b * b - (ox * ox + oy * oy - r * r)
        with np.errstate(invalid="ignore"):
            t = -b - np.sqrt(disc)
        best = np.where((disc >= 0) & (t > 0) & (t < best), t, best)
    for x0, y0, x1, y1 in world.segments:
        ex, ey = x1 - x0, y1 - y0
        den = dx * ey - dy * ex
        with np.errstate(divide="ignore", invalid="ignore"):
            t = ((x0 - x) * ey - (y0 - y) * ex) / den
            u = ((x0 - x) * dy - (y0 - y) * dx) / den
        ok = (np.abs(den) > 1e-12) & (t > 0) & (u >= 0) & (u <= 1) & (t < best)
        best = np.where(ok, t, best)
    best = np.where(best <= range_max, best, np.inf)
    return Scan(stamp_ns=stamp_ns, angle_min=-math.pi, angle_increment=inc,
                range_min=RANGE_MIN_M, range_max=range_max, ranges=best.astype(np.float32))


@dataclass
class SimResult:
    path: np.ndarray                   # (N, 3) x, y, yaw per scan [m, m, rad]
    status: str                        # last planner status
    time_s: float                      # sim time at the end [s]
    min_clearance: float               # closest approach to an obstacle surface [m]
    states: list = field(default_factory=list)  # PlannerState per cycle if kept

    @property
    def length(self) -> float:
        return float(np.sum(np.hypot(*np.diff(self.path[:, :2], axis=0).T)))


def simulate(planner, world: ToyWorld, start=(0.0, 0.0, 0.0), goal=(5.0, 0.0),
             tolerance: float = 0.1, max_time_s: float = 120.0, keep_states: bool = False,
             beams: int = 300) -> SimResult:
    """Closed loop: scan -> planner.step -> unicycle for one scan period, until an outcome."""
    x, y, yaw = map(float, start)
    planner.set_goal(Goal(stamp_ns=0, x=goal[0], y=goal[1], tolerance=tolerance))
    dt = SCAN_PERIOD_NS / 1e9
    path, states, status, t = [(x, y, yaw)], [], "driving", 0
    clearance = world.clearance(x, y)
    while t <= max_time_s * 1e9:
        scan = cast_scan(world, x, y, yaw, t, beams)
        cmd, state, st = planner.step(scan, Odometry(stamp_ns=t, x=x, y=y, yaw=yaw, v=0.0, w=0.0))
        status = st.state
        if keep_states:
            states.append(state)
        if status in ("reached", "stagnated", "failed"):
            break
        x, y, yaw = _unicycle(x, y, yaw, cmd.v, cmd.w, dt)
        path.append((x, y, yaw))
        clearance = min(clearance, world.clearance(x, y))
        t += SCAN_PERIOD_NS
    return SimResult(np.array(path), status, t / 1e9, clearance, states)


def _unicycle(x, y, yaw, v, w, dt):
    """Exact integration of a unicycle with constant (v, w) over dt."""
    if abs(w) < 1e-9:
        return x + v * dt * math.cos(yaw), y + v * dt * math.sin(yaw), yaw
    yaw2 = yaw + w * dt
    return (x + v / w * (math.sin(yaw2) - math.sin(yaw)),
            y - v / w * (math.cos(yaw2) - math.cos(yaw)), yaw2)
