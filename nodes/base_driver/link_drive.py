"""What the rosbot driver does with commands during a run (pure; time passed in).

One object per driver joins the three robot-side parts of docs/link-driving.md: the
:class:`~nodes.base_driver.follow.PlanFollower` (which command, followed how), the
:class:`~nodes.base_driver.monitor.CollisionMonitor` (the robot's own scan, last) and the
:class:`~common.linkstats.LinkStats` (what the link did). Time is the robot's run time [ns].
Every method returns the events to publish as ``(kind, detail)``; the driver stamps them.
"""

from __future__ import annotations

import math

import numpy as np

from common.linkstats import LinkStats
from nodes.base_driver.follow import FollowSettings, PlanFollower
from nodes.base_driver.monitor import CollisionMonitor, MonitorSettings
from schemas import LinkHealth, Scan, Twist

Pose = tuple[float, float, float]
LOG_EVERY = 100    # after the first 5, one refused command in this many gets a log line


class LinkDriving:
    """Commands in, (v, w) per control tick out, with the events that say why (module doc)."""

    def __init__(self, watchdog_ns: int, follow: FollowSettings | None = None,
                 monitor: MonitorSettings | None = None):
        self.watchdog_ns = watchdog_ns
        self.follow_settings, self.monitor_settings = follow, monitor
        self.start()

    def start(self) -> None:
        """A new run: no command, no scan, fresh statistics."""
        self.follower = PlanFollower(self.watchdog_ns, self.follow_settings)
        self.monitor = CollisionMonitor(self.monitor_settings)
        self.stats = LinkStats("robot", self.watchdog_ns)
        self.stopped_why: str | None = None     # the current stop episode's reason
        self.stopped_at: int | None = None      # ... when it began, and why then
        self.stop_reason = ""
        self.scale = 1.0
        self.refused = 0
        self.stopped_ns = 0                     # run time the follower held the base still
        self.last_control: int | None = None

    # -- inputs -------------------------------------------------------------------------------
    def command(self, cmd: Twist, now_ns: int, pose: Pose | None = None) -> list[tuple[str, str]]:
        """A command arriving at run time ``now_ns`` (the robot at ``pose``): taken or refused
        (``command_refused``)."""
        verdict, why = self.follower.take(cmd, now_ns, self.monitor.fresh(now_ns), pose)
        events = [self._told(kind, detail) for kind, detail in
                  self.stats.command(now_ns, cmd.stamp_ns, verdict, answers_scan=bool(cmd.plan))]
        if verdict != "obeyed":
            self.refused += 1
            events.append(("command_refused", f"{verdict}: cmd_vel of {cmd.stamp_ns * 1e-9:.3f} s "
                           f"({cmd.v:.3f} m/s, {cmd.w:.3f} rad/s): {why}"))
        return events

    def _told(self, kind: str, detail: str) -> tuple[str, str]:
        """``link_restored`` also says what the robot did meanwhile: the other side's
        recording missed the robot's own events of the outage."""
        if kind == "link_restored" and self.stopped_at is not None:
            detail += (f"; the robot stopped the base at {self.stopped_at * 1e-9:.2f} s "
                       f"({self.stop_reason})")
        return kind, detail

    def scan(self, scan: Scan, now_ns: int, pose: Pose | None) -> None:
        """The robot's own scan (taken at ``scan.stamp_ns``), the robot at world ``pose``."""
        if pose is None or scan.stamp_ns > now_ns:
            return
        self.monitor.scan(scan.stamp_ns, scan_points(scan), pose)

    # -- each control tick --------------------------------------------------------------------
    def control(self, now_ns: int, pose: Pose | None) -> tuple[float, float, list[tuple[str, str]]]:
        """(v, w) for the base at ``now_ns`` and the events of this tick."""
        events = self.stats.tick(now_ns)
        fresh = self.monitor.fresh(now_ns)
        target = self.follower.target(now_ns, pose, fresh)
        self.scale = target.scale
        if target.why and self.follower.cmd is not None and self.last_control is not None:
            self.stopped_ns += now_ns - self.last_control   # held still by the link
        self.last_control = now_ns
        if target.why:
            if self.stopped_why is None and self.follower.cmd is not None:
                events.append(("watchdog_stop", f"stopping the base: {target.why}"))
                self.stopped_at, self.stop_reason = now_ns, target.why
            self.stopped_why = target.why
            return 0.0, 0.0, events
        self.stopped_why, self.stopped_at = None, None
        v, w = target.v, target.w
        if fresh and pose is not None:
            v, w, _, _ = self.monitor.check(v, w, pose)
        return v, w, events

    def health(self, now_ns: int) -> LinkHealth:
        return self.stats.report(now_ns, self.scale, self.monitor.stops, self.stopped_ns * 1e-9)

    def should_log(self) -> bool:
        """Whether the latest refusal deserves a log line (the first 5, then 1 in LOG_EVERY)."""
        return self.refused <= 5 or self.refused % LOG_EVERY == 0


def scan_points(scan: Scan) -> np.ndarray:
    """The scan's valid returns (finite, within its range limits) in the robot frame, (N, 2)."""
    r = np.asarray(scan.ranges, dtype=float)
    a = scan.angle_min + scan.angle_increment * np.arange(r.size) + scan.sensor_yaw
    ok = np.isfinite(r) & (r >= scan.range_min) & (r <= scan.range_max)
    r, a = r[ok], a[ok]
    return np.column_stack((scan.sensor_x + r * np.cos(a), scan.sensor_y + r * np.sin(a)))


def world_pose(x: float, y: float, yaw: float) -> Pose | None:
    """A finite pose or None."""
    return (x, y, yaw) if all(map(math.isfinite, (x, y, yaw))) else None
