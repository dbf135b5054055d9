"""Decide a run's outcome and figures from its messages (pure; no zenoh).

The outcome is fixed at a sim time ``t_end`` (docs/architecture.md, "Start and end
of a run") and every figure is taken at exactly ``t_end``, so two runs with the
same seed give identical summaries whatever the process scheduling.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

from common.units import NS_PER_S as NS
from schemas import BatteryState, Clock, Event, Odometry, PlannerStatus, Twist

MOVING_SPEED = 0.01  # [m/s] |v| above which the robot counts as moving (duration_s starts)

OUTCOMES = ("reached", "stagnated", "collision", "timeout", "failed")
EXIT_CODES = {"reached": 0, "stagnated": 3, "collision": 4, "timeout": 5, "failed": 6}


@dataclass
class RunResult:
    """The summary of one run; ``to_json()`` is the fixed `papf run --json` object."""

    outcome: str
    planner: str
    world: str
    seed: int
    duration_s: float          # from the first motion to the outcome [s, sim time]
    path_length_m: float       # ground-truth path length up to the outcome [m]
    charge_mAh: float          # charge drawn up to the outcome [mAh]
    energy_J: float            # energy drawn up to the outcome [J]
    collisions: int
    sim_time_s: float          # sim time of the outcome [s]
    wall_time_s: float         # wall time of the whole run, start-up included [s]
    reason: str = ""
    stop_latency_s: float | None = None  # last command -> watchdog stop, after a planner fault
    faults: tuple[str, ...] = ()         # node_fault events (e.g. a lockstep timeout)

    @property
    def exit_code(self) -> int:
        return EXIT_CODES.get(self.outcome, 6)

    def to_json(self) -> dict:
        d = asdict(self)
        for k in ("duration_s", "path_length_m", "charge_mAh", "energy_J", "sim_time_s",
                  "wall_time_s"):
            d[k] = round(d[k], 6)
        if d["stop_latency_s"] is None:
            del d["stop_latency_s"]
        if d["faults"]:  # a fault (e.g. lockstep timeout) makes the run not bit-reproducible
            d["faults"] = list(d["faults"])
        else:
            del d["faults"]
        return d


class RunMonitor:
    """Feed it the run's messages (any order per topic is fine except per-topic order)."""

    def __init__(self, timeout_s: float, stop_on_collision: bool = True):
        self.timeout_ns = int(round(timeout_s * NS))
        self.stop_on_collision = stop_on_collision
        self.outcome: str | None = None
        self.reason = ""
        self.t_end_ns: int | None = None
        self.clock_ns = -1
        self.status: PlannerStatus | None = None
        self.collisions: list[int] = []
        self.batteries: list[BatteryState] = []
        self._poses: list[Odometry] = []
        self.last_cmd_ns: int | None = None
        self.watchdog_stop_ns: int | None = None
        self.faults: list[str] = []

    # -- inputs ---------------------------------------------------------------
    def on_clock(self, msg: Clock) -> None:
        self.clock_ns = max(self.clock_ns, msg.stamp_ns)
        if self.outcome is None and msg.stamp_ns >= self.timeout_ns:
            self._decide("timeout", self.timeout_ns, f"no outcome within {self.timeout_ns / NS:g} s")

    def on_status(self, msg: PlannerStatus) -> None:
        self.status = msg
        if msg.state in ("reached", "stagnated", "failed"):
            self._decide(msg.state, msg.stamp_ns, msg.reason)

    def on_event(self, msg: Event) -> None:
        if msg.kind == "collision":
            self.collisions.append(msg.stamp_ns)
            if self.stop_on_collision:
                self._decide("collision", msg.stamp_ns,
                             f"collision at ({msg.x:.2f}, {msg.y:.2f}) {msg.detail}".strip())
        elif msg.kind == "watchdog_stop" and self.watchdog_stop_ns is None:
            self.watchdog_stop_ns = msg.stamp_ns
        elif msg.kind == "node_fault":
            self.faults.append(f"{msg.source} at {msg.stamp_ns / NS:.2f} s: {msg.detail}")

    def on_battery(self, msg: BatteryState) -> None:
        self.batteries.append(msg)

    def on_pose(self, msg: Odometry) -> None:
        self._poses.append(msg)

    def on_cmd(self, msg: Twist) -> None:
        self.last_cmd_ns = msg.stamp_ns if self.last_cmd_ns is None else max(self.last_cmd_ns,
                                                                             msg.stamp_ns)

    def fail(self, reason: str) -> None:
        """A non-deterministic failure (a node died, the stack stalled)."""
        self._decide("failed", max(self.clock_ns, 0), reason)

    def _decide(self, outcome: str, t_ns: int, reason: str) -> None:
        if self.outcome is None or t_ns < (self.t_end_ns or 0):
            self.outcome, self.t_end_ns, self.reason = outcome, t_ns, reason

    # -- outputs --------------------------------------------------------------
    @property
    def done(self) -> bool:
        return self.outcome is not None

    def figures_complete(self) -> bool:
        """True once battery and pose samples reach ``t_end`` (figures are then final)."""
        if self.t_end_ns is None:
            return False
        return (bool(self.batteries) and self.batteries[-1].stamp_ns >= self.t_end_ns
                and bool(self._poses) and self._poses[-1].stamp_ns >= self.t_end_ns)

    def battery_at_end(self) -> BatteryState | None:
        best = None
        for b in self.batteries:
            if b.stamp_ns <= (self.t_end_ns or 0):
                best = b
        return best

    def path_length_m(self) -> float:
        total, prev = 0.0, None
        for p in self._poses:
            if p.stamp_ns > (self.t_end_ns or 0):
                break
            if prev is not None:
                total += math.hypot(p.x - prev.x, p.y - prev.y)
            prev = p
        return total

    def motion_start_ns(self) -> int | None:
        return next((p.stamp_ns for p in self._poses if abs(p.v) > MOVING_SPEED), None)

    def distance_to(self, x: float, y: float) -> float:
        if not self._poses:
            return math.nan
        return math.hypot(self._poses[-1].x - x, self._poses[-1].y - y)

    def robot_stopped(self) -> bool:
        return bool(self._poses) and abs(self._poses[-1].v) < MOVING_SPEED and abs(
            self._poses[-1].w) < 0.05

    def result(self, planner: str, world: str, seed: int, wall_time_s: float) -> RunResult:
        t_end = self.t_end_ns or 0
        battery = self.battery_at_end()
        start = self.motion_start_ns()
        latency = None
        if self.watchdog_stop_ns is not None and self.last_cmd_ns is not None:
            latency = (self.watchdog_stop_ns - self.last_cmd_ns) / NS
            if latency < 0:  # the stop belonged to an earlier outage the run recovered from
                latency = None
        return RunResult(
            outcome=self.outcome or "failed", planner=planner, world=world, seed=seed,
            duration_s=max(0, t_end - start) / NS if start is not None else 0.0,
            path_length_m=self.path_length_m(),
            charge_mAh=battery.charge_used_mAh if battery else math.nan,
            energy_J=battery.energy_J if battery else math.nan,
            collisions=sum(1 for c in self.collisions if c <= t_end),
            sim_time_s=t_end / NS, wall_time_s=wall_time_s, reason=self.reason,
            stop_latency_s=latency, faults=tuple(self.faults),
        )
