"""``papf experiment energy``: the PAPF paper's 3-run energy experiment (IV-C), in sim.

Each planner × ``runs`` on world ``energy`` through the full process stack, recorded,
then the report (:func:`papf.report.report.build_report`) from the files alone.
Details: :func:`run_experiment`.
"""

from __future__ import annotations

import contextlib
import logging
import math
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from common.errors import ConfigError
from nodes.energy_meter.models import DEFAULT_MODEL, MODELS
from nodes.planner.registry import PLANNERS, one_with_role
from papf.experiments.journal import Journal, run_key
from papf.experiments.sweep import SweepOptions

if TYPE_CHECKING:  # heavy imports (zenoh, matplotlib, rich) wait until a run: `papf --help` stays fast
    from rich.console import Console
    from rich.progress import Progress

    from papf.launch.outcome import RunResult
    from papf.launch.run import RunConfig
    from papf.report.report import Report

WORLD = "energy"
TIMEOUT_S = 300.0        # [s sim] per run; the sim's APF needs ~160 s for the 10 m course
POLL_S = 0.1             # [s wall] progress refresh period


#: the PAPF paper's comparison (Sec. IV-C): its baseline and PAPF, by their declared roles
PAPER_PAIR = (one_with_role("papf-baseline"), one_with_role("papf-proposed"))


@dataclass(frozen=True)
class EnergyExperiment:
    out: Path
    runs: int = 3
    planners: tuple[str, ...] = PAPER_PAIR
    seed: int = 0
    world: str = WORLD
    timeout_s: float = TIMEOUT_S
    energy_model: str = DEFAULT_MODEL
    presets: tuple[str, ...] = ("default",)
    sweep: SweepOptions = SweepOptions()   # how the runs are spread (papf.experiments.sweep)


@dataclass(frozen=True)
class RunSpec:
    planner: str
    k: int            # 1-based run number of this planner
    seed: int
    path: Path        # where the run is recorded
    preset: str = "default"

    @property
    def name(self) -> str:
        """The experiment's name (its file's stem)."""
        return self.path.stem


@dataclass
class ExperimentResult:
    results: list[tuple[RunSpec, RunResult]]
    report: Report
    wall_s: float
    mismatches: list[str] = field(default_factory=list)   # live vs report disagreements

    @property
    def exit_code(self) -> int:
        """0, or 6 if a run failed (the stack, not the planner) or the report disagrees."""
        failed = any(r.outcome == "failed" for _s, r in self.results)
        return 6 if failed or self.mismatches else 0


def validate(exp: EnergyExperiment) -> None:
    """ConfigError naming the bad value (before any process starts)."""
    if exp.runs < 1:
        raise ConfigError(f"--runs {exp.runs}: need at least 1 run per planner")
    if not exp.planners:
        raise ConfigError(f"--planners is empty; e.g. {','.join(PAPER_PAIR)}")
    unknown = [p for p in exp.planners if p not in PLANNERS]
    if unknown:
        raise ConfigError(f"unknown planner(s) {', '.join(unknown)}; valid: {', '.join(PLANNERS)}")
    if len(set(exp.planners)) != len(exp.planners):
        raise ConfigError(f"--planners {','.join(exp.planners)} names a planner twice")
    from nodes.planner.registry import PRESETS

    bad = [p for p in exp.presets if p not in PRESETS]
    if bad or not exp.presets:
        raise ConfigError(f"--presets {','.join(exp.presets)}: unknown {bad}; valid: {list(PRESETS)}")
    if exp.energy_model not in MODELS:
        raise ConfigError(f"energy model {exp.energy_model!r} is not one of motor, paper")
    if not exp.timeout_s > 0:
        raise ConfigError(f"timeout {exp.timeout_s} s must be > 0")


def plan(exp: EnergyExperiment) -> list[RunSpec]:
    """Every run, planner (and preset) by planner: ``OUT/<planner>[-<preset>]-<k>.mcap`` with
    seed ``seed + k``. A planner whose paper preset changes nothing runs once."""
    from papf.experiments.trials import variants

    def stem(p, preset):
        return p if preset == "default" else f"{p}-{preset}"

    return [RunSpec(p, k, exp.seed + k, Path(exp.out) / f"{stem(p, pre)}-{k}.mcap", pre)
            for p, pre in variants(exp.planners, exp.presets) for k in range(1, exp.runs + 1)]


def run_config(exp: EnergyExperiment, spec: RunSpec, port: int) -> RunConfig:
    """The RunConfig of one run of ``exp`` (world, planner, preset, seed) on router ``port``."""
    from nodes.planner.registry import preset_sets
    from papf.experiments.trials import LOCKSTEP_TIMEOUT_S
    from papf.launch.run import RunConfig

    return RunConfig(world=exp.world, planner=spec.planner, seed=spec.seed,
                     planner_args=[a for kv in preset_sets(spec.preset) for a in ("--set", kv)],
                     timeout_s=exp.timeout_s, record=str(spec.path), force=True, port=port,
                     energy_model=exp.energy_model, progress=False,
                     lockstep_timeout_s=LOCKSTEP_TIMEOUT_S,   # the runs share the cores
                     extra_node_args={"recorder": ["--meta", "experiment=energy"]})


class LiveFigures:
    """Latest clock, charge and pose of a run, from a subscriber on the run's router."""

    def __init__(self, port: int, namespace: str = "rosbot"):
        self.endpoint, self.ns, self.port = f"tcp/127.0.0.1:{port}", namespace, port
        self.sim_s, self.charge_mAh, self.xy = 0.0, 0.0, (math.nan, math.nan)
        self._session = None
        self._subs: list = []

    def connect(self, abort: Callable[[], bool]) -> bool:
        """Once the run's router listens; False if the run ended first or Zenoh refused."""
        import zenoh

        from common.transport import zenoh_config
        from papf.launch.supervisor import wait_port
        from schemas import BatteryState, Clock, Odometry

        if not wait_port(self.port, 60.0, abort=abort):
            return False
        try:
            self._session = zenoh.open(zenoh_config("client", [self.endpoint]))
        except Exception:  # the live line is a nicety; the run goes on without it
            return False
        subs = {"clock": (Clock, lambda m: setattr(self, "sim_s", m.stamp_ns * 1e-9)),
                "battery": (BatteryState, lambda m: setattr(self, "charge_mAh", m.charge_used_mAh)),
                "sim/pose": (Odometry, lambda m: setattr(self, "xy", (m.x, m.y)))}
        for topic, (msg_type, store) in subs.items():
            self._subs.append(self._session.declare_subscriber(f"{self.ns}/{topic}",
                                                               _decoding(msg_type, store)))
        return True

    def text(self, goal: tuple[float, float]) -> str:
        """The progress line: sim time [s], distance to ``goal`` [m], charge [mAh]."""
        dist = math.hypot(self.xy[0] - goal[0], self.xy[1] - goal[1])
        to_goal = f"{dist:5.2f} m to goal" if math.isfinite(dist) else "starting"
        return f"sim {self.sim_s:6.1f} s  {to_goal}  {self.charge_mAh:6.2f} mAh"

    def close(self) -> None:
        """Undeclare the subscribers and close the session (the run's router may be gone)."""
        with contextlib.suppress(Exception):  # the run's router is gone by now
            for sub in self._subs:
                sub.undeclare()
            if self._session is not None:
                self._session.close()
        self._subs.clear()
        self._session = None


def _decoding(msg_type, store):
    def on_sample(sample) -> None:
        try:
            store(msg_type.from_bytes(sample.payload.to_bytes()))
        except Exception:  # a bad payload is not this watcher's business
            pass
    return on_sample


def _one_run(exp: EnergyExperiment, spec: RunSpec, progress: Progress, task,
             goal: tuple[float, float], run_fn: Callable[[RunConfig], RunResult]) -> RunResult:
    from papf.launch.supervisor import run_port

    port = run_port()
    box: dict[str, object] = {}

    def target() -> None:
        try:
            box["result"] = run_fn(run_config(exp, spec, port))
        except BaseException as exc:  # re-raised on the main thread
            box["error"] = exc

    worker = threading.Thread(target=target, name=f"run-{spec.name}", daemon=True)
    worker.start()
    live = LiveFigures(port)
    try:
        live.connect(abort=lambda: not worker.is_alive())
        while worker.is_alive():
            progress.update(task, live=f"{spec.name} (seed {spec.seed}): {live.text(goal)}")
            worker.join(POLL_S)
    finally:
        live.close()
    if "error" in box:
        raise box["error"]  # type: ignore[misc]
    return box["result"]  # type: ignore[return-value]


def run_experiment(exp: EnergyExperiment, console: Console | None = None,
                   run_fn: Callable[[RunConfig], RunResult] | None = None) -> ExperimentResult:
    """Run every planner × runs through the stack, recorded, then write the report.

    ``run_fn``: how one run is made (default :func:`papf.launch.run.run`; tests substitute).

    World ``energy`` (goal (10, 0) m, three obstacles); each planner × ``runs``; run k
    (1-based) of every planner uses seed ``seed + k`` (the same noise for the k-th run of
    each planner: paired runs); each run goes through the full process stack
    (:func:`papf.launch.run.run`) recorded to ``OUT/<planner>-<k>.mcap``; then the report
    (:func:`papf.report.report.build_report`) from those files alone, in ``OUT``.

    While a run goes, a progress bar over the runs shows its live figures (sim time,
    distance to the goal, charge), read from the run's own router by a Zenoh subscriber
    of this process; each run's result is printed as it finishes. The run's summary
    (live) and the report's figures for it (from the file) are compared at the end.
    """
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    from papf.launch.run import run
    from papf.report.report import build_report
    from worlds import load_world

    run_fn = run_fn or run

    validate(exp)
    exp.sweep.validate()
    console = console or Console(stderr=True)
    world = load_world(exp.world)
    out = Path(exp.out)
    out.mkdir(parents=True, exist_ok=True)
    specs = plan(exp)
    _warn_foreign_files(out, specs, console)
    own = _report_is_ours(out, exp.world)   # before any run: not after the last one
    wall0 = time.monotonic()
    if exp.sweep.distributed:
        results = _run_spread(exp, specs, console)
        report = build_report([s.path for s, _r in results], out, force=own)
        return ExperimentResult(results, report, time.monotonic() - wall0,
                                _mismatches(results, report))
    results: list[tuple[RunSpec, RunResult]] = []
    columns = (TextColumn("[bold]energy experiment[/]"), BarColumn(bar_width=16), MofNCompleteColumn(),
               TimeElapsedColumn(), TextColumn("{task.fields[live]}"))
    run_log = logging.getLogger("papf.run")
    level = run_log.level
    run_log.setLevel(logging.WARNING)  # the runner's every-10-s lines; the bar shows them
    try:
        with Progress(*columns, console=console, transient=True) as progress:
            task = progress.add_task("runs", total=len(specs), live="")
            journal = Journal(out)
            for spec in specs:
                result = _resumed(journal, exp, spec)
                if result is None:
                    result = _one_run(exp, spec, progress, task, world.goal[:2], run_fn)
                    journal.put(_spec_key(exp, spec), journal_entry(result))   # as it ends
                results.append((spec, result))
                progress.advance(task)
                console.print(_result_line(spec, result), highlight=False, soft_wrap=True)
    finally:
        run_log.setLevel(level)
    report = build_report([s.path for s, _r in results], out, force=own)
    wall = time.monotonic() - wall0
    return ExperimentResult(results, report, wall, _mismatches(results, report))


def _run_spread(exp: EnergyExperiment, specs: list[RunSpec], console: Console) -> list:
    """Every run on Dask (:mod:`papf.experiments.sweep`), recorded where it runs, each file
    written here under its usual name: the report sees the same files as a sequential one."""
    from papf.experiments.sweep import map_runs

    jobs = [(exp, spec, i) for i, spec in enumerate(specs)]
    done = map_runs(energy_job, jobs, exp.sweep, label=lambda j: f"{j[1].name} seed {j[1].seed}",
                    title="energy experiment")
    results = []
    for spec, (result, data) in zip(specs, done, strict=True):
        if data is not None:
            spec.path.write_bytes(data)
        results.append((spec, result))
        console.print(_result_line(spec, result), highlight=False)
    return results


def energy_job(job: tuple[EnergyExperiment, RunSpec, int]) -> tuple[RunResult, bytes | None]:
    """One recorded run of a spread experiment: (its result, its recording's bytes)."""
    import dataclasses
    import tempfile

    from papf.experiments.sweep import run_namespace
    from papf.launch.run import run
    from papf.launch.supervisor import run_port

    exp, spec, index = job
    with tempfile.TemporaryDirectory(prefix="papf-energy-") as tmp:
        local = dataclasses.replace(spec, path=Path(tmp) / spec.path.name)
        cfg = dataclasses.replace(run_config(exp, local, run_port()),
                                  namespace=run_namespace(index))
        result = run(cfg)
        return result, (local.path.read_bytes() if local.path.exists() else None)


def _spec_key(exp: EnergyExperiment, spec: RunSpec) -> str:
    from worlds import world_path

    return run_key(world_path(exp.world).read_text(encoding="utf-8"), spec.planner, spec.seed,
                   spec.preset, spec.path.name, exp.timeout_s, exp.energy_model)


#: the figures a resumed run is checked with against its recording (``_mismatches``)
EXACT_FIGURES = ("duration_s", "path_length_m", "charge_mAh", "energy_J", "sim_time_s",
                 "wall_time_s")


def journal_entry(result: RunResult) -> dict:
    """A finished run as the journal keeps it: the run's JSON with its figures unrounded
    (JSON floats round-trip exactly), so that a resumed run's figures still equal what its
    recording gives to :data:`papf.report.metrics.REPRODUCE_TOL` (the JSON's 6 decimals
    would not: a resumed experiment would call every run a mismatch and exit 6)."""
    entry = result.to_json()
    for k in EXACT_FIGURES:
        v = getattr(result, k)
        if math.isfinite(v):
            entry[k] = v
    return entry


def _resumed(journal: Journal, exp: EnergyExperiment, spec: RunSpec) -> RunResult | None:
    """A run finished before (its recording and its result on disk), or None."""
    from papf.launch.outcome import RunResult

    data = journal.get(_spec_key(exp, spec))
    if data is None or not spec.path.is_file():
        return None
    try:
        import dataclasses

        names = {f.name for f in dataclasses.fields(RunResult)}
        kw = {k: (math.nan if v is None else v) for k, v in data.items() if k in names}
        kw["faults"] = tuple(kw.get("faults", ()))
        return RunResult(**kw)
    except (TypeError, ValueError):
        return None


def _report_is_ours(out: Path, world: str) -> bool:
    """Whether a report already in ``out`` is this experiment's (its journal ``out/runs/`` is
    there: an earlier run of it wrote the report, which the new one replaces); a report in
    ``out`` without the journal is someone's own: refused (OutputError) before any run."""
    from common.outfiles import OutputError
    from papf.report.report import report_files
    from worlds import load_world

    if (out / "runs").is_dir():
        return True
    there = [n for n in report_files([load_world(world).name], "") if (out / n).exists()]
    if there:
        raise OutputError(f"{out} already holds a report ({', '.join(there)}) that this "
                          "experiment did not make; give another --out, or move those files")
    return False


def _warn_foreign_files(out: Path, specs: Sequence[RunSpec], console: Console) -> None:
    ours = {s.path.name for s in specs}
    other = sorted(p.name for p in out.glob("*.mcap") if p.name not in ours)
    if other:
        from rich.markup import escape

        note = (f"{out} also holds {', '.join(other)}; this experiment's report covers its own "
                f"{len(specs)} runs, but `papf report {out}` would include those too")
        console.print(f"[yellow]note:[/] {escape(note)}")


def _result_line(spec: RunSpec, r: RunResult) -> str:
    """A finished run's line (rich markup: the outcome coloured, the rest escaped)."""
    from rich.markup import escape

    colour = "green" if r.outcome == "reached" else "red"
    return (f"{escape(f'{spec.name:>8} seed {spec.seed:<3}')} [{colour}]{r.outcome:<9}[/] "
            f"{r.duration_s:7.2f} s  {r.path_length_m:6.2f} m  {r.charge_mAh:7.3f} mAh  "
            f"{r.energy_J:7.1f} J  wall {r.wall_time_s:4.1f} s"
            + (f"  {escape(r.reason)}" if r.outcome != "reached" else ""))


def _mismatches(results: Sequence[tuple[RunSpec, RunResult]], report: Report) -> list[str]:
    """Runs whose figures in the report differ from the live summary (should be none)."""
    from papf.report.metrics import differences_from_live

    by_file = {m.file: m for m in report.runs}
    bad = []
    for spec, live in results:
        m = by_file.get(spec.path.name)
        bad += ([f"{spec.name}: not in the report"] if m is None
                else differences_from_live(spec.name, live, m))
    return bad


def print_summary(res, console=None) -> None:
    """The experiment's table (mean ± sd), PAPF vs APF next to the paper, and the wall time."""
    from rich.console import Console  # rich: only to print
    from rich.markup import escape  # "[mAh]" is text, not a style tag
    from rich.table import Table

    from papf.console.tables import print_table
    from papf.report.tables import PAPER, change_pct

    console = console or Console()
    model = res.report.model
    t = Table(title=escape(f"energy experiment on "
                           f"{', '.join(sorted({s.world for s in res.report.summaries}))}"
                           f" (runs that reached the goal: mean ± sd; {model} model)"))
    for col in ("planner", "reached", f"charge [mAh, {model}]", f"energy [J, {model}]",
                "duration [s]", "path [m]"):
        t.add_column(escape(col), justify="right")
    for s in res.report.summaries:
        st = s.stats
        t.add_row(escape(s.planner), f"{s.reached}/{s.runs}", st["charge_mAh"].text(".2f"),
                  st["energy_J"].text(".1f"), st["duration_s"].text(".2f"),
                  st["path_length_m"].text(".3f"))
    print_table(t, console)   # fits the terminal; piped: one line a row
    apf, papf = (res.report.summary(name) for name in PAPER_PAIR)
    if apf and papf:
        for attr, label in (("charge_mAh", "charge"), ("duration_s", "duration"),
                            ("path_length_m", "path length")):
            console.print(f"PAPF vs APF {label}: {change_pct(apf.stats[attr], papf.stats[attr]):+.1f} %"
                          f"   paper: {PAPER[attr]}", highlight=False)
    for m in res.mismatches:
        console.print(f"[red]report differs from the live run:[/] {escape(m)}")
    console.print(f"report: {escape(str(res.report.files[-1]))}", highlight=False)
    console.print(f"wall time: {res.wall_s:.1f} s for {len(res.results)} runs and the report",
                  highlight=False)
