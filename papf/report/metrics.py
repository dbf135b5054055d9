"""Per-run figures of a recorded run, from its MCAP file alone (docs/recording.md, docs/experiments-energy.md).

Outcome, ``t_end``, duration, path length and the live battery at ``t_end`` are decided
by feeding the recording to :class:`papf.launch.outcome.RunMonitor` — the very object
``papf run`` uses live — so a report and the run's own summary agree by construction.
Charge and energy are re-metered from the recorded ``odom`` + ``wheels``
(:mod:`papf.report.remeter`). Smoothness and heading oscillations are computed here
from the recorded odometry (definitions in :func:`smoothness` and
:func:`heading_oscillations`).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from common.errors import PapfError, RecordingError
from nodes.energy_meter.models import DEFAULT_MODEL
from papf.launch.outcome import MOVING_SPEED, NS, RunMonitor
from papf.recording.reader import Recording, decode
from papf.recording.rosbag import (
    BagRecording,
    TopicMap,
    is_rosbag,
    measured_charge_mAh,
    open_run,
)
from papf.report.remeter import Remeter, battery_at
from papf.report.sides import Segment, in_window
from schemas import (
    BatteryState,
    BatteryVoltage,
    Clock,
    Event,
    Odometry,
    People,
    PlannerStatus,
    Twist,
    WheelStates,
)
from worlds import load_world

OSCILLATION_W_RAD_S = 0.1   # [rad/s] |w| a swing must exceed to count (ASSUMPTION: well above
                            # the sim's straight-line yaw corrections, ~0.02 rad/s; 5.7 deg/s)
REPRODUCE_TOL = 1e-9        # [-] relative: a file's figure vs the live run's summary
NO_TIMEOUT_S = 1e9          # [s] stands for "no timeout known" (the monitor needs a number)
NO_OUTCOME = "no_outcome"   # the recording ends before any outcome message (timeout unknown)
INCOMPLETE = "incomplete"   # ... and before the run's timeout: the recording lost the end
BAG = "bag"                 # a rosbag2 recorded on the robot: no outcome, figures over the bag


@dataclass(frozen=True)
class Series:
    """Time series of one run up to ``t_end`` (for figures). Arrays of equal length."""

    t_s: np.ndarray          # [s] sim time
    x: np.ndarray            # [m] pose from RunMetrics.pose_source (sim/pose or odom)
    y: np.ndarray            # [m]
    heading: np.ndarray      # [rad] unwrapped yaw
    v: np.ndarray            # [m/s] odometry forward speed
    w: np.ndarray            # [rad/s] odometry yaw rate
    # the people of the run (``sim/people``), every PEOPLE_EVERY_NS: (T, n, 2) [m], and each
    # one's radius at each sample (T, n) [m] (0: a replayed person not in the scene)
    people: np.ndarray | None = None
    people_r: np.ndarray | None = None


PEOPLE_EVERY_NS = 500_000_000   # [ns] the people kept for the trajectories' picture

UNKNOWN_WORLD = "unknown"   # a recording without the launcher's metadata (papf record, no --meta)
MID_RUN_NS = 1_000_000_000  # [ns] a recording whose first stamp is later began mid-run


@dataclass
class RunMetrics:
    """Everything the report states about one run (units in the names)."""

    file: str
    planner: str
    world: str
    seed: int
    outcome: str
    reason: str
    t_end_s: float              # [s] sim time of the outcome
    duration_s: float           # [s] first motion -> outcome (papf.launch.outcome definition)
    path_length_m: float        # [m] ground-truth path up to t_end
    charge_mAh: float           # [mAh] re-metered with ``energy_model`` at t_end
    energy_J: float             # [J] re-metered
    mean_power_W: float         # [W] energy_J over the recorded time: from t = 0, or from the
                                #     first message of a recording started mid-run
    live_charge_mAh: float      # [mAh] last recorded live battery with stamp <= t_end (nan: none)
    live_energy_J: float        # [J]
    live_stamp_s: float         # [s] its stamp (< t_end when the recorder stopped before the
                                #     meter's last messages reached it)
    live_model: str             # model the live meter ran ("" if no battery recorded)
    remeter_diff_mAh: float     # [mAh] re-metered minus live charge at live_stamp_s (0: exact)
    energy_model: str           # model used for charge_mAh / energy_J
    pose_source: str            # where path and trajectory come from: sim/pose (ground truth)
                                #     or odom (odometry: a real robot has no ground truth)
    ang_accel_sq: float         # [rad^2/s^3] integral of (dw/dt)^2 over the motion
    jerk_sq: float              # [m^2/s^5] integral of (d^2v/dt^2)^2 over the motion
    heading_oscillations: int   # sign changes of w beyond +-OSCILLATION_W_RAD_S
    collisions: int
    measured_charge_mAh: float | None = None   # [mAh] ∫ current dt of a bag's /battery over
                                               #     its odometry; None: no current measured
    series: Series | None = field(default=None, repr=False, compare=False)
    robot: str = field(default="", compare=False)   # a fleet's robot (namespace); "" alone
    recorded_from_s: float = field(default=0.0, compare=False)   # [s] first message of a
                                    # recording begun mid-run (0: it holds the run's start)
    sides: dict | None = field(default=None, compare=False)   # recorded on the laptop and on
                                    # the robot: where each figure came from (papf.report.sides)

    def row(self) -> dict:
        """Flat dict of the scalar figures (CSV row; a fleet's robot is in ``file``)."""
        d = asdict(self)
        for name in ("series", "robot", "recorded_from_s", "sides"):
            d.pop(name)
        return d


def smoothness(t_s: np.ndarray, v: np.ndarray, w: np.ndarray) -> tuple[float, float]:
    """(∫ β² dt [rad²/s³], ∫ j² dt [m²/s⁵]) by finite differences of sampled v, w.

    β = dω/dt is the angular acceleration of eq. (6)'s I ω β term; j = d²v/dt² the
    linear jerk. Both integrals are 0 for a motion at constant speeds and grow with every
    swing of the commands (the paper's "unsmooth and oscillating motion"). Differences
    of samples: β_k = Δω_k / Δt_k over each interval (weight Δt_k); a_k = Δv_k / Δt_k at
    interval midpoints, j_k = Δa_k / (midpoint spacing) (weight: that spacing). Values
    depend on the sample rate (odometry at 50 Hz): compare runs recorded at one rate only.
    """
    t = np.asarray(t_s, dtype=float)
    if t.size < 3:
        return 0.0, 0.0
    dt = np.diff(t)
    beta = np.diff(w) / dt
    ang = float(np.sum(beta**2 * dt))
    a = np.diff(v) / dt
    t_mid = 0.5 * (t[1:] + t[:-1])
    dtm = np.diff(t_mid)
    jerk = np.diff(a) / dtm
    return ang, float(np.sum(jerk**2 * dtm))


def heading_oscillations(w: np.ndarray, threshold: float = OSCILLATION_W_RAD_S) -> int:
    """Times the yaw rate swings from beyond +threshold to beyond -threshold or back.

    Samples with |w| <= threshold are ignored (hysteresis), so sensor-level wiggles
    around zero and one-sided turns count nothing; a left-right-left weave counts 2.
    """
    arr = np.asarray(w, dtype=float)
    signs = np.sign(arr[np.abs(arr) > threshold])
    return int(np.count_nonzero(signs[1:] != signs[:-1])) if signs.size else 0


def _unwrap_heading(yaw: list[float]) -> np.ndarray:
    return np.unwrap(np.asarray(yaw, dtype=float)) if yaw else np.zeros(0)


class _Collector:
    """One pass over a recording: feeds the monitor, the re-meter and the series."""

    def __init__(self, ns: str, timeout_s: float, remeter: Remeter):
        self.timeout_known = timeout_s < NO_TIMEOUT_S
        self.monitor = RunMonitor(timeout_s)
        self.remeter = remeter
        self.odom: list[Odometry] = []
        self.poses: list[Odometry] = []
        self.ground_truth = False       # poses came from sim/pose (else from odom)
        self.first_ns: int | None = None   # [ns] earliest stamp recorded
        self.run_started = False        # the recording holds the run's run_started event
        self.people: list[People] = []  # sim/people every PEOPLE_EVERY_NS (the picture)
        m = self.monitor
        self.handlers = {f"{ns}/clock": (Clock, m.on_clock),
                         f"{ns}/planner/status": (PlannerStatus, m.on_status),
                         f"{ns}/events": (Event, m.on_event),
                         f"{ns}/battery": (BatteryState, m.on_battery),
                         f"{ns}/sim/pose": (Odometry, self._on_sim_pose),
                         f"{ns}/cmd_vel": (Twist, m.on_cmd),
                         f"{ns}/odom": (Odometry, self._on_odom),
                         f"{ns}/wheels": (WheelStates, self.remeter.feed),
                         f"{ns}/battery/measured": (BatteryVoltage, self.remeter.measured),
                         f"{ns}/sim/people": (People, self._on_people)}

    def _on_people(self, msg: People) -> None:
        if msg.stamp_ns % PEOPLE_EVERY_NS == 0 and (
                not self.people or len(msg.x) == len(self.people[0].x)):
            self.people.append(msg)

    def _on_sim_pose(self, msg: Odometry) -> None:
        self.ground_truth = True
        self._on_pose(msg)

    def _on_pose(self, msg: Odometry) -> None:
        self.poses.append(msg)
        self.monitor.on_pose(msg)

    def _on_odom(self, msg: Odometry) -> None:
        self.odom.append(msg)
        self.remeter.feed(msg)

    def feed(self, key: str, msg: object) -> None:
        msg_type, handler = self.handlers[key]
        if isinstance(msg, msg_type):  # undecodable payloads arrive as bytes: skip them
            stamp = msg.stamp_ns
            self.first_ns = stamp if self.first_ns is None else min(self.first_ns, stamp)
            self.run_started = self.run_started or (isinstance(msg, Event)
                                                    and msg.kind == "run_started")
            handler(msg)

    @property
    def mid_run(self) -> bool:
        """The recording began after the run did (no run_started, first stamp past 0)."""
        return not self.run_started and (self.first_ns or 0) > MID_RUN_NS

    def finish(self) -> None:
        """No outcome message: the run ended at its last clock (or odometry) stamp."""
        m = self.monitor
        if not self.poses:  # a real robot has no ground truth: odometry is the path
            for o in self.odom:
                self._on_pose(o)
        if m.outcome is None:
            last = max([m.clock_ns] + [o.stamp_ns for o in self.odom[-1:]])
            m.outcome, m.t_end_ns = NO_OUTCOME, max(last, 0)
            m.reason = "the recording ends before any outcome (timeout, or a stopped run)"
            if self.timeout_known:  # the run went on to an outcome the file does not hold
                m.outcome = INCOMPLETE
                m.reason = (f"the recording ends at {last / NS:.2f} s, before any outcome and "
                            f"before the timeout ({m.timeout_ns / NS:g} s): its end was lost")


def fleet_namespaces(path: str | Path, topics: TopicMap | None = None) -> list[str]:
    """The robots of a fleet's recording (every ``<ns>`` with an ``<ns>/odom`` channel) when
    it holds more than one, else [] (one robot's recording, or a rosbag2)."""
    if is_rosbag(path, topics):
        return []
    with open_run(path, topics) as rec:
        if isinstance(rec, BagRecording):
            return []
        names = sorted({k[: -len("/odom")] for k in rec.keys() if k.endswith("/odom")})
    return names if len(names) > 1 else []


def run_facts(path: str | Path, topics: TopicMap | None = None) -> tuple[str, str]:
    """A recording's (world, live meter's model) as :func:`run_metrics` will find them, read
    from its metadata (else its first battery message) alone: the names of a report's files
    are known before any figure is computed (``papf report`` refuses an existing one first)."""
    with open_run(path, topics) as rec:
        meta = rec.run_metadata
        world = meta.get("world", UNKNOWN_WORLD)
        if isinstance(rec, BagRecording):
            return world, ""
        ns = meta.get("namespace") or _guess_namespace(rec)
        return world, _live_model(rec, ns, fleet_namespaces(path, topics))


def _live_model(rec: Recording, ns: str, robots: list[str]) -> str:
    """The model of the last battery message of the run (the live meter's: what
    :class:`RunMetrics` ``live_model`` holds); a fleet's: its first robot's."""
    for _key, msg, _t in rec.messages([f"{robots[0] if robots else ns}/battery"]):
        if isinstance(msg, BatteryState):
            return msg.model   # one meter per run: its first message names its model
    return ""


def run_metrics(path: str | Path, energy_model: str | None = None,
                energy_params: dict | None = None, with_series: bool = True,
                topics: TopicMap | None = None, robot: str | None = None,
                window: Segment | None = None) -> RunMetrics:
    """Figures of the run recorded in ``path`` (see the module doc), or of a rosbag2
    (:func:`papf.recording.rosbag.open_run`, its topics mapped by ``topics``); of a fleet's
    recording, robot ``robot``'s (its planner: the world's ``[[robots]]`` entry's, if any).

    ``energy_model``: ``paper`` | ``motor`` | None (the model the live meter ran, from the
    run metadata). ``window``: one run of a robot's black box (:mod:`papf.report.sides`).
    Raises RecordingError for a truncated or foreign file.
    """
    with open_run(path, topics) as rec:
        meta = rec.run_metadata
        ns = robot or meta.get("namespace") or _guess_namespace(rec)
        if robot:
            meta = {**meta, "planner": _robot_planner(meta, robot)}
        model = energy_model or meta.get("energy_model") or _recorded_model(rec, ns) or DEFAULT_MODEL
        timeout_s = float(meta.get("timeout_s") or NO_TIMEOUT_S)
        col = _Collector(ns, timeout_s, Remeter(model, energy_params))
        for key, msg, _t in _messages(rec, list(col.handlers), window):
            col.feed(key, msg)
        bag = _bag_figures(rec, col) if isinstance(rec, BagRecording) else None
    col.finish()
    m = _assemble(Path(path), meta, col, model, with_series)
    if robot:
        m.file, m.robot = f"{m.file}:{robot}", robot
    if bag is not None:
        m.outcome, m.reason = BAG, "a rosbag2 recorded on the robot: figures over its odometry"
        m.duration_s, m.measured_charge_mAh = bag
    return m


def _messages(rec, keys: list[str], window: Segment | None):
    """The recording's messages on ``keys``; within ``window`` (wall receive time) if given."""
    if window is None:
        yield from rec.messages(keys)
        return
    for raw in rec.raw(keys):
        if in_window(raw.publish_time_ns, window):
            yield raw.key, decode(raw.schema_name, raw.data), raw.log_time_ns


def _robot_planner(meta: dict, robot: str) -> str:
    """A fleet robot's planner: its ``[[robots]]`` entry's in the recorded world, else the run's."""
    try:
        fleet = load_world(meta["world"]).robots
    except (KeyError, PapfError):
        fleet = ()
    own = next((r.planner for r in fleet if r.name == robot and r.planner), None)
    return own or meta.get("planner", "unknown")


def _bag_figures(rec: BagRecording, col: _Collector) -> tuple[float, float | None]:
    """A bag's (duration [s]: first to last odometry sample moving faster than
    MOVING_SPEED, measured charge [mAh] over its odometry or None)."""
    moving = [o.stamp_ns for o in col.odom if abs(o.v) > MOVING_SPEED]
    duration = (moving[-1] - moving[0]) / NS if moving else 0.0
    if not col.odom:
        return duration, None
    span = (col.odom[0].stamp_ns, col.odom[-1].stamp_ns)
    return duration, measured_charge_mAh(rec.battery_currents(), *span)


def _recorded_model(rec: Recording | BagRecording, ns: str) -> str:
    """The model the live meter ran, from its first recorded battery message ("" if none)."""
    for _key, msg, _t in rec.messages([f"{ns}/battery"]):
        if isinstance(msg, BatteryState):
            return msg.model
    return ""


def seed_text(seed: int) -> str:
    """A seed for people: "?" when the recording did not say (stored as -1)."""
    return "?" if seed < 0 else str(seed)


def _guess_namespace(rec: Recording | BagRecording) -> str:
    odom = [k for k in rec.keys() if k.endswith("/odom")]
    if not odom:
        raise RecordingError(f"{rec.path}: no '<namespace>/odom' channel; is this a papf run "
                             f"recording? keys: {', '.join(rec.keys()[:8]) or 'none'}")
    return odom[0][: -len("/odom")]


def _assemble(path: Path, meta: dict, col: _Collector, model: str,
              with_series: bool) -> RunMetrics:
    m = col.monitor
    t_end = m.t_end_ns or 0
    planner = meta.get("planner", "unknown")
    if "preset=paper" in meta.get("planner_args", ""):
        planner += " (paper)"            # the variant label of papf.experiments.trials
    res = m.result(planner, meta.get("world", UNKNOWN_WORLD), int(meta.get("seed", -1)), 0.0)
    t0 = col.first_ns if col.mid_run else 0      # [ns] where the recorded figures start
    if col.mid_run and res.outcome == "reached":
        res.outcome = "partial"
        res.reason = (f"the recording starts at {t0 / NS:.2f} s, after the run began: the goal "
                      "was reached, but path, duration and charge cover only the recorded part")
    remetered = battery_at(col.remeter.states, t_end)
    live = m.battery_at_end()
    start_ns = m.motion_start_ns()
    moving = [o for o in col.odom if start_ns is not None and start_ns <= o.stamp_ns <= t_end]
    t = np.array([o.stamp_ns / NS for o in moving])
    v = np.array([o.v for o in moving])
    w = np.array([o.w for o in moving])
    ang, jerk = smoothness(t, v, w)
    energy = remetered.energy_J if remetered else math.nan
    return RunMetrics(
        file=path.name, planner=res.planner, world=res.world, seed=res.seed,
        outcome=res.outcome, reason=res.reason, t_end_s=t_end / NS,
        duration_s=res.duration_s, path_length_m=res.path_length_m,
        charge_mAh=remetered.charge_used_mAh if remetered else math.nan, energy_J=energy,
        mean_power_W=energy / ((t_end - t0) / NS) if t_end > t0 else math.nan,
        live_charge_mAh=live.charge_used_mAh if live else math.nan,
        live_energy_J=live.energy_J if live else math.nan,
        live_stamp_s=live.stamp_ns / NS if live else math.nan,
        live_model=live.model if live else "", energy_model=model,
        pose_source="sim/pose" if col.ground_truth else "odom",
        remeter_diff_mAh=_remeter_diff(col.remeter.states, live),
        ang_accel_sq=ang, jerk_sq=jerk, heading_oscillations=heading_oscillations(w),
        collisions=res.collisions,
        series=_series(col.poses, col.odom, t_end, col.people) if with_series else None,
        recorded_from_s=t0 / NS,
    )


def metadata_notes(m: RunMetrics) -> list[str]:
    """What the report of ``m`` cannot know, said plainly (empty for a launcher's recording)."""
    notes = []
    if m.world == UNKNOWN_WORLD:
        notes.append(f"{m.file}: world unknown: recorded without the launcher's metadata "
                     "(papf record FILE --meta world=W --meta planner=P names them)")
    if m.recorded_from_s > 0:
        unit = f" ({m.energy_model} model)"
        notes.append(
            f"{m.file}: begun mid-run: it holds {m.recorded_from_s:.2f}-{m.t_end_s:.2f} s of a "
            f"run that started before it (no run_started); over that part: path "
            f"{m.path_length_m:.2f} m, charge {m.charge_mAh:.2f} mAh, mean power "
            f"{m.mean_power_W:.2f} W{unit}, from its first message; outcome {m.outcome}: "
            f"{m.reason}")
    return notes


def live_difference(m: RunMetrics, tol_mAh: float = 0.01) -> str:
    """Why the report's charge of ``m`` differs from the live figure ("" when they agree).

    The report's charge is the re-metered one at the outcome ``t_end_s``; the live figure
    is the meter's last recorded message at or before it (``live_stamp_s``). The difference
    splits into the charge drawn between the two stamps and the re-meter Δ at the live
    stamp (messages the live meter and the recorder did not both see).
    """
    if m.energy_model != m.live_model or m.recorded_from_s > 0 or not (
            math.isfinite(m.charge_mAh) and math.isfinite(m.live_charge_mAh)):
        return ""   # a recording begun mid-run: the live meter counted from before it
    diff = m.charge_mAh - m.live_charge_mAh
    if abs(diff) <= tol_mAh:
        return ""
    meter = m.remeter_diff_mAh if math.isfinite(m.remeter_diff_mAh) else 0.0
    return (f"{m.file}: charge {m.charge_mAh:.2f} mAh here vs {m.live_charge_mAh:.2f} mAh live "
            f"({diff:+.2f}): {diff - meter:+.2f} mAh drawn between the live meter's last figure "
            f"({m.live_stamp_s:.2f} s) and the outcome ({m.t_end_s:.2f} s), {meter:+.2f} mAh "
            "from re-metering the recorded messages (what the live meter received and the "
            "recorder kept differ)")


def _remeter_diff(states: list[BatteryState], live: BatteryState | None) -> float:
    if live is None:
        return math.nan
    same = battery_at(states, live.stamp_ns)
    if same is None or same.stamp_ns != live.stamp_ns:
        return math.nan
    return same.charge_used_mAh - live.charge_used_mAh


def _series(poses: list[Odometry], odom: list[Odometry], t_end: int,
            people: list[People] = ()) -> Series:
    poses = [p for p in poses if p.stamp_ns <= t_end]
    by_stamp = {o.stamp_ns: o for o in odom if o.stamp_ns <= t_end}
    both = [(p, by_stamp[p.stamp_ns]) for p in poses if p.stamp_ns in by_stamp]
    crowd = [m for m in people if m.stamp_ns <= t_end]
    return Series(t_s=np.array([p.stamp_ns / NS for p, _ in both]),
                  x=np.array([p.x for p, _ in both]), y=np.array([p.y for p, _ in both]),
                  heading=_unwrap_heading([p.yaw for p, _ in both]),
                  v=np.array([o.v for _, o in both]), w=np.array([o.w for _, o in both]),
                  people=np.array([np.column_stack([m.x, m.y]) for m in crowd]) if crowd
                  else None,
                  people_r=np.array([m.radius for m in crowd], float) if crowd else None)


def differences_from_live(name: str, live, m: RunMetrics,
                          rel_tol: float = REPRODUCE_TOL) -> list[str]:
    """Figures of a run's file that differ from its live summary (:class:`papf.launch.outcome.RunResult`).

    Empty when the recording holds the whole run: the monitor and the meter then see the
    same messages as they did live (charge/energy compared for the same energy model).
    """
    bad = []
    for attr in ("outcome", "duration_s", "path_length_m", "charge_mAh", "energy_J"):
        a, b = getattr(live, attr), getattr(m, attr)
        same = a == b if isinstance(a, str) else (
            math.isclose(a, b, rel_tol=rel_tol, abs_tol=1e-12) or (math.isnan(a) and math.isnan(b)))
        if not same:
            bad.append(f"{name}: {attr} live {a} vs file {b}")
    return bad
