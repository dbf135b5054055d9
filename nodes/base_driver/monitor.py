"""Robot-side collision monitor on the robot's own latest scan (pure; docs/link-driving.md).

Like Nav2's ``collision_monitor``, the last check before the base, whatever the command:

- **stop zone**: the footprint (``common.robot`` BODY_LENGTH x BODY_WIDTH) grown by
  ``stop_margin``. A return inside it ahead of the centre forbids driving forward (behind:
  backward); a return inside the circle the body sweeps when turning in place (half the
  diagonal + margin) forbids turning;
- **approach** (Nav2's ``approach`` model): the command (v, w) is rolled forward as an arc
  for ``time_before_collision``; if the grown footprint would touch a return after ``t_c``
  seconds, the command is scaled by ``t_c / time_before_collision``, so the robot slows as
  it closes in and never reaches the return at the commanded speed.

Returns are kept in the run's world frame (the robot's pose when the scan came), so the
robot's own motion since the scan is accounted for. No fresh scan: :meth:`CollisionMonitor.fresh`
is False and the follower falls back to commands no older than the watchdog.

Its settings are safety settings: every value in their ranges keeps the monitor on (a
margin of at least 2 cm, at least 0.5 s of look-ahead, a scan at most 1 s old).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from common import robot
from common.errors import ConfigError
from common.params import check_value, num

SPECS = {
    "stop_margin": num(0.02, 0.5, "m", safety=True),
    "time_before_collision": num(0.5, 5.0, "s", safety=True),
    "scan_timeout": num(0.05, 1.0, "s", safety=True),
}
STEP_S = 0.05          # [s] the approach check's time step (2.5 cm at 0.5 m/s)
TURN_IN_PLACE_M_S = 0.05   # [m/s] slower than this, a turn counts as in place
HALF_L = 0.5 * robot.BODY_LENGTH_M
HALF_W = 0.5 * robot.BODY_WIDTH_M


@dataclass(frozen=True)
class MonitorSettings:
    stop_margin: float = 0.05            # [m] (ours: a wheel's width short of the body)
    time_before_collision: float = 1.2   # [s] (ours; Nav2's example uses 1.2 s)
    scan_timeout: float = 0.5            # [s] an older scan is not the robot's view (Nav2: source_timeout)

    def __post_init__(self) -> None:
        for name, spec in SPECS.items():
            check_value(name, getattr(self, name), spec)


class Verdict(NamedTuple):
    v: float
    w: float
    action: str     # "" (unchanged), "stop", "slow"
    detail: str


class CollisionMonitor:
    """Keeps the latest scan's returns; :meth:`check` limits a command against them."""

    def __init__(self, settings: MonitorSettings | None = None):
        self.s = settings or MonitorSettings()
        self.points = np.zeros((0, 2))      # returns in the world frame
        self.scan_ns: int | None = None     # run time the scan was taken
        self.stops = 0                      # checks that stopped or slowed a command

    def scan(self, stamp_ns: int, points_robot: np.ndarray, pose: tuple[float, float, float]) -> None:
        """Take a scan's returns ``points_robot`` (N, 2) [m] in the robot frame, the robot
        at world ``pose`` (x, y, yaw) when it was taken."""
        if points_robot.size and not np.isfinite(points_robot).all():
            raise ConfigError("scan points must be finite")
        x, y, yaw = pose
        c, s = math.cos(yaw), math.sin(yaw)
        p = np.asarray(points_robot, dtype=float).reshape(-1, 2)
        self.points = np.column_stack((x + c * p[:, 0] - s * p[:, 1], y + s * p[:, 0] + c * p[:, 1]))
        self.scan_ns = stamp_ns

    def fresh(self, now_ns: int) -> bool:
        """A scan no older than ``scan_timeout`` at run time ``now_ns``."""
        return self.scan_ns is not None and 0 <= now_ns - self.scan_ns <= self.s.scan_timeout * 1e9

    def check(self, v: float, w: float, pose: tuple[float, float, float]) -> Verdict:
        """(v, w) limited by the returns around the robot at world ``pose``.

        Only the speed is scaled on approach: turning away stays possible (the planner's
        way out); a turn in place is refused only when the body would sweep a return.
        """
        if not self.points.shape[0] or (v == 0.0 and w == 0.0):
            return Verdict(v, w, "", "")
        local = _to_robot(self.points, pose)
        v0 = v
        v, reasons = _stop_zone(local, v, self.s.stop_margin)
        if v != 0.0 and (t_c := self._time_to_collision(local, v, w)) is not None:
            v *= t_c / self.s.time_before_collision
            reasons.append(f"a return {t_c:.2f} s ahead at {v0:.2f} m/s")
        if (w != 0.0 and abs(v) < TURN_IN_PLACE_M_S
                and np.any(np.hypot(local[:, 0], local[:, 1])
                           < robot.FOOTPRINT_RADIUS_M + self.s.stop_margin)):
            w = 0.0
            reasons.append("a return within the turning circle")
        if not reasons:
            return Verdict(v, w, "", "")
        self.stops += 1
        action = "stop" if v == 0.0 and (v0 != 0.0 or w == 0.0) else "slow"
        return Verdict(v, w, action, "; ".join(reasons))

    def _time_to_collision(self, local: np.ndarray, v: float, w: float) -> float | None:
        """First time [s] the grown footprint, driving the arc (v, w), contains a return."""
        steps = int(math.ceil(self.s.time_before_collision / STEP_S))
        # returns already in the zone are the stop zone's (judged by side); reach = the arc's length
        reach = abs(v) * self.s.time_before_collision + robot.FOOTPRINT_RADIUS_M + self.s.stop_margin
        near = local[(np.hypot(local[:, 0], local[:, 1]) < reach)
                     & ~_in_box(local, self.s.stop_margin)]
        if not near.shape[0]:
            return None
        for k in range(1, steps + 1):
            t = k * STEP_S
            pose = _arc(v, w, t)
            if np.any(_in_box(_to_robot(near, pose), self.s.stop_margin)):
                return max(0.0, t - STEP_S)
        return None


def _stop_zone(local: np.ndarray, v: float, margin: float) -> tuple[float, list[str]]:
    """v set to 0 when the stop zone holds a return on the side it drives to, and why."""
    inside = _in_box(local, margin)
    if v > 0.0 and np.any(inside & (local[:, 0] > 0.0)):
        return 0.0, ["a return in the stop zone ahead"]
    if v < 0.0 and np.any(inside & (local[:, 0] < 0.0)):
        return 0.0, ["a return in the stop zone behind"]
    return v, []


def _arc(v: float, w: float, t: float) -> tuple[float, float, float]:
    if abs(w) < 1e-9:
        return v * t, 0.0, 0.0
    return v / w * math.sin(w * t), v / w * (1.0 - math.cos(w * t)), w * t


def _to_robot(points: np.ndarray, pose: tuple[float, float, float]) -> np.ndarray:
    x, y, yaw = pose
    c, s = math.cos(yaw), math.sin(yaw)
    dx, dy = points[:, 0] - x, points[:, 1] - y
    return np.column_stack((c * dx + s * dy, -s * dx + c * dy))


def _in_box(local: np.ndarray, margin: float) -> np.ndarray:
    return (np.abs(local[:, 0]) <= HALF_L + margin) & (np.abs(local[:, 1]) <= HALF_W + margin)
