"""Decide a run's outcome and figures from its messages (pure; no zenoh).

The outcome is fixed at a sim time ``t_end`` (docs/architecture.md, "Start and end
of a run") and every figure is taken at exactly ``t_end``, so two runs with the
same seed give identical summaries whatever the process scheduling.

Trust: given the world's goal, a planner's ``reached`` counts only when the ground truth
(the pose samples: sim pose, or odometry on the robot) at that stamp lies within the
goal's tolerance; a refuted claim is counted, not obeyed. Memory is constant however
long a run lasts: pose and battery samples are kept in ring buffers (:data:`POSE_WINDOW`,
:data:`BATTERY_WINDOW`) with the path length as a running sum.
"""

from __future__ import annotations

import math
from bisect import bisect_right
from collections import deque
from dataclasses import asdict, dataclass, field

from common.outcomes import EXIT_CODES
from common.robot import MOVING_SPEED
from common.units import NS_PER_S as NS
from schemas import BatteryState, Clock, Event, Goal, Odometry, PlannerStatus, Twist

POSE_WINDOW = 4096     # [-] pose samples kept: 82 s at 50 Hz, far more than the launcher lags
BATTERY_WINDOW = 4096  # [-] battery samples kept
MAX_FAULTS = 20        # [-] node_fault events kept verbatim (the rest are counted)
GOAL_SLACK_M = 1e-6    # [m] rounding allowance of the ground-truth goal check



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
    fleet: tuple[dict, ...] = ()         # a fleet's robots, one object each (papf.launch.fleet)
    min_separation_m: float | None = None  # a fleet: closest footprint approach [m]
    discomfort_s: float | None = None    # a fleet: time people spent within 0.2 m of a robot [s]
    run_id: str = ""                     # the run's id (hex; common.seal), on every sealed sample
    refused: dict = field(default_factory=dict)   # {process: {topic: {reason: n}}}: samples
    # not sealed by this run's processes (foreign, replayed, another run's), dropped
    recording: dict | None = None        # --record: file, complete, messages, dropped per key
    link: dict | None = None             # a split run: the link's health (papf.launch.linkwatch)
    link_emulator: dict | None = None    # papf run --link: what the emulated link did (papf.link)

    @property
    def exit_code(self) -> int:
        return EXIT_CODES.get(self.outcome, 6)

    def to_json(self) -> dict:
        """Plain JSON: a missing figure (e.g. no battery sample) is null, never NaN."""
        d = asdict(self)
        for k in ("duration_s", "path_length_m", "charge_mAh", "energy_J", "sim_time_s",
                  "wall_time_s"):
            d[k] = round(d[k], 6) if math.isfinite(d[k]) else None
        if d["stop_latency_s"] is None:
            del d["stop_latency_s"]
        if d["link_emulator"] is None:   # only a run over papf link has one
            del d["link_emulator"]
        if d["faults"]:  # a fault (e.g. lockstep timeout) makes the run not bit-reproducible
            d["faults"] = list(d["faults"])
        else:
            del d["faults"]
        if d["recording"] is None:
            del d["recording"]
        if d["link"] is None:   # runs on one host: no link to speak of
            del d["link"]
        fleet = d.pop("fleet")
        if fleet:   # several robots: the fleet's figures and one object per robot
            d["min_separation_m"] = (round(self.min_separation_m, 6)
                                     if self.min_separation_m is not None else None)
            d["discomfort_s"] = round(self.discomfort_s or 0.0, 6)
            d["robots"] = fleet
        else:
            del d["min_separation_m"], d["discomfort_s"]
        return d


class _Pose:
    """A pose sample with the path length driven up to it (running sum)."""

    __slots__ = ("stamp_ns", "x", "y", "v", "w", "path_m")

    def __init__(self, msg: Odometry, path_m: float):
        self.stamp_ns, self.x, self.y, self.v, self.w = msg.stamp_ns, msg.x, msg.y, msg.v, msg.w
        self.path_m = path_m


class RunMonitor:
    """Feed it the run's messages (any order per topic is fine except per-topic order).

    ``goal``: the world's goal ``(x, y, tolerance)``; with it, ``reached`` needs ground
    truth (module doc).
    """

    def __init__(self, timeout_s: float, stop_on_collision: bool = True,
                 goal: tuple[float, float, float] | None = None):
        self.timeout_ns = int(round(timeout_s * NS))
        self.stop_on_collision = stop_on_collision
        self.goal = goal
        self.outcome: str | None = None
        self.reason = ""
        self.t_end_ns: int | None = None
        self.clock_ns = -1
        self.status: PlannerStatus | None = None
        self.collisions: deque[int] = deque(maxlen=BATTERY_WINDOW)
        self._old_collisions = 0              # collisions pushed out of the window
        self.batteries: deque[BatteryState] = deque(maxlen=BATTERY_WINDOW)
        self._poses: deque[_Pose] = deque(maxlen=POSE_WINDOW)
        self._motion_start_ns: int | None = None
        self._claims: deque[PlannerStatus] = deque(maxlen=BATTERY_WINDOW)  # "reached" claims
        # waiting for their pose sample, each judged on its own (whatever arrives first)
        self.refuted_claims = 0               # "reached" claims the ground truth denied
        self.last_cmd_ns: int | None = None
        self.watchdog_stop_ns: int | None = None
        self.faults: list[str] = []
        self.more_faults = 0
        self._path0 = 0.0                     # [m] driven before this launcher (a resumed run)
        self._resume_xy: tuple[float, float] | None = None

    def resume(self, path_m: float, motion_start_ns: int | None,
               last_xy: tuple[float, float] | None = None) -> None:
        """Go on with a run another launcher began (:mod:`papf.launch.resume`): its path so
        far, its first motion, and where its last pose sample was — the way from there to
        this launcher's first pose counts as a straight line (the robot drove it unseen)."""
        self._path0 = max(0.0, float(path_m))
        self._motion_start_ns = motion_start_ns
        self._resume_xy = last_xy

    def last_xy(self) -> tuple[float, float] | None:
        return (self._poses[-1].x, self._poses[-1].y) if self._poses else None

    def path_so_far(self) -> float:
        """The path driven up to the newest pose sample [m]."""
        return self._poses[-1].path_m if self._poses else self._path0

    # -- inputs ---------------------------------------------------------------
    def on_clock(self, msg: Clock) -> None:
        self.on_time(msg.stamp_ns)

    def on_time(self, stamp_ns: int) -> None:
        """Sim time has reached ``stamp_ns`` (a clock message, or in sim a pose sample)."""
        self.clock_ns = max(self.clock_ns, stamp_ns)
        if self.outcome is None and stamp_ns >= self.timeout_ns:
            self._decide("timeout", self.timeout_ns, f"no outcome within {self.timeout_ns / NS:g} s")

    def on_status(self, msg: PlannerStatus) -> None:
        self.status = msg
        if msg.state == "reached" and self.goal is not None:
            self._claims.append(msg)
            self._check_claim()
        elif msg.state in ("reached", "stagnated", "failed"):
            self._decide(msg.state, msg.stamp_ns, msg.reason)

    def on_event(self, msg: Event) -> None:
        if msg.kind == "collision":
            if len(self.collisions) == self.collisions.maxlen:
                self._old_collisions += 1
            self.collisions.append(msg.stamp_ns)
            if self.stop_on_collision:
                self._decide("collision", msg.stamp_ns,
                             f"collision at ({msg.x:.2f}, {msg.y:.2f}) {msg.detail}".strip())
        elif msg.kind == "watchdog_stop" and self.watchdog_stop_ns is None:
            self.watchdog_stop_ns = msg.stamp_ns
        elif msg.kind == "node_fault":
            if len(self.faults) < MAX_FAULTS:
                self.faults.append(f"{msg.source} at {msg.stamp_ns / NS:.2f} s: {msg.detail}")
            else:
                self.more_faults += 1

    def on_battery(self, msg: BatteryState) -> None:
        self.batteries.append(msg)

    def on_pose(self, msg: Odometry) -> None:
        last = self._poses[-1] if self._poses else None
        if last is None:
            gap = (0.0 if self._resume_xy is None else
                   math.hypot(msg.x - self._resume_xy[0], msg.y - self._resume_xy[1]))
            path = self._path0 + gap
        else:
            path = last.path_m + math.hypot(msg.x - last.x, msg.y - last.y)
        self._poses.append(_Pose(msg, path))
        if self._motion_start_ns is None and abs(msg.v) > MOVING_SPEED:
            self._motion_start_ns = msg.stamp_ns
        if self._claims:
            self._check_claim()

    def on_goal(self, msg: Goal) -> None:
        """A goal of this run (verified by the caller) replaces the one judged against."""
        if self.goal is not None:
            self.goal = (msg.x, msg.y, msg.tolerance)

    def on_cmd(self, msg: Twist) -> None:
        self.last_cmd_ns = msg.stamp_ns if self.last_cmd_ns is None else max(self.last_cmd_ns,
                                                                             msg.stamp_ns)

    def fail(self, reason: str, at_ns: int | None = None) -> None:
        """A non-deterministic failure (a node died, the stack stalled), at sim time
        ``at_ns`` (default: the clock now), never past the timeout."""
        t = max(self.clock_ns, 0) if at_ns is None else max(at_ns, 0)
        self._decide("failed", min(t, self.timeout_ns), reason)

    def _decide(self, outcome: str, t_ns: int, reason: str) -> None:
        if self.outcome is None or t_ns < (self.t_end_ns or 0):
            self.outcome, self.t_end_ns, self.reason = outcome, t_ns, reason

    def _check_claim(self) -> None:
        """Judge each waiting ``reached`` claim by the pose sample at its stamp, once that
        arrived. Every claim is judged, even when a later one came first (statuses and poses
        travel on different links), and the earliest accepted one decides (``_decide``)."""
        if not self._poses:
            return
        newest = self._poses[-1].stamp_ns
        waiting = [c for c in self._claims if c.stamp_ns > newest]
        for claim in [c for c in self._claims if c.stamp_ns <= newest]:
            pose = self._pose_at(claim.stamp_ns)
            x, y, tol = self.goal
            if pose is not None and math.hypot(pose.x - x, pose.y - y) <= tol + GOAL_SLACK_M:
                self._decide("reached", claim.stamp_ns, claim.reason)
            else:
                self.refuted_claims += 1
        self._claims = deque(waiting, maxlen=BATTERY_WINDOW)

    def _pose_at(self, t_ns: int) -> _Pose | None:
        """The last pose sample with ``stamp <= t_ns`` still in the window, or None."""
        poses = self._poses
        i = bisect_right([p.stamp_ns for p in poses], t_ns) if poses[0].stamp_ns <= t_ns else 0
        return poses[i - 1] if i else None

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
        if not self._poses:
            return self._path0
        pose = self._pose_at(self.t_end_ns or 0)
        return pose.path_m if pose is not None else 0.0

    def motion_start_ns(self) -> int | None:
        return self._motion_start_ns

    def distance_to(self, x: float, y: float) -> float:
        if not self._poses:
            return math.nan
        return math.hypot(self._poses[-1].x - x, self._poses[-1].y - y)

    def robot_stopped(self) -> bool:
        return bool(self._poses) and abs(self._poses[-1].v) < MOVING_SPEED and abs(
            self._poses[-1].w) < 0.05

    def last_stamp(self, topic: str) -> int | None:
        """Stamp of the newest sample of a figure's topic (``battery``, ``pose``, ``status``)."""
        newest = {"battery": self.batteries[-1] if self.batteries else None,
                  "pose": self._poses[-1] if self._poses else None,
                  "status": self.status}[topic]
        return None if newest is None else newest.stamp_ns

    def result(self, planner: str, world: str, seed: int, wall_time_s: float) -> RunResult:
        t_end = self.t_end_ns or 0
        battery = self.battery_at_end()
        start = self.motion_start_ns()
        latency = None
        if self.watchdog_stop_ns is not None and self.last_cmd_ns is not None:
            latency = (self.watchdog_stop_ns - self.last_cmd_ns) / NS
            if latency < 0:  # the stop belonged to an earlier outage the run recovered from
                latency = None
        faults = tuple(self.faults) + ((f"... and {self.more_faults} more node faults",)
                                       if self.more_faults else ())
        return RunResult(
            outcome=self.outcome or "failed", planner=planner, world=world, seed=seed,
            duration_s=max(0, t_end - start) / NS if start is not None else 0.0,
            path_length_m=self.path_length_m(),
            charge_mAh=battery.charge_used_mAh if battery else math.nan,
            energy_J=battery.energy_J if battery else math.nan,
            collisions=self._old_collisions + sum(1 for c in self.collisions if c <= t_end),
            sim_time_s=t_end / NS, wall_time_s=wall_time_s, reason=self.reason,
            stop_latency_s=latency, faults=faults,
        )
