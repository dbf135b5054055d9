"""One run of a planner on a world as a :class:`Trial` — offline or through the stack.

One :class:`Trial` per (world, planner, seed), run either offline (:func:`run_offline`,
:func:`papf.offline.run.simulate`) or through the full process stack (:func:`run_stack`,
:func:`papf.launch.run.run` on a free port, recorded to MCAP so the ground-truth path can be
drawn); plus the CSV / Markdown writers and the progress bar the experiments share.
"""

from __future__ import annotations

import csv
import dataclasses
import logging
import math
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

from common.errors import RecordingError
from common.outfiles import output, replace_text
from papf.experiments.journal import Journal, run_key
from papf.experiments.sweep import SweepOptions, map_runs
from papf.launch.supervisor import run_port
from worlds import World, load_world

MODES = ("offline", "stack")


@dataclass
class Trial:
    """One run of one planner on one world."""

    world: str
    planner: str
    seed: int
    mode: str                       # offline | stack
    outcome: str                    # reached | stagnated | collision | timeout | failed
    duration_s: float               # first motion -> outcome [s sim time]
    path_length_m: float
    collisions: int
    reason: str = ""
    min_clearance_m: float = math.nan   # offline only [m]
    charge_mAh: float = math.nan        # stack only [mAh]
    wall_time_s: float = 0.0
    path: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))  # (N, 2|3) [m]
    preset: str = "default"             # planner preset (nodes.planner.registry.PRESETS)

    @property
    def label(self) -> str:
        """``planner`` for the default preset, ``planner (paper)`` otherwise (table rows)."""
        return variant_label(self.planner, self.preset)

    def row(self) -> dict:
        """The CSV row (no path)."""
        # No wall time: a row depends on the run alone, so a sweep's CSV is byte-identical
        # however its runs were spread (papf.experiments.sweep).
        return {"world": self.world, "planner": self.planner, "preset": self.preset,
                "seed": self.seed, "mode": self.mode,
                "outcome": self.outcome, "duration_s": round(self.duration_s, 3),
                "path_length_m": round(self.path_length_m, 3), "collisions": self.collisions,
                "min_clearance_m": _r(self.min_clearance_m), "charge_mAh": _r(self.charge_mAh),
                "reason": self.reason}


def _r(x: float, nd: int = 3):
    return "" if x is None or not math.isfinite(x) else round(x, nd)


def variant_label(planner: str, preset: str) -> str:
    """``papf`` for the default preset, else ``papf (paper)``."""
    return planner if preset == "default" else f"{planner} ({preset})"


def variants(planners: Sequence[str], presets: Sequence[str] = ("default",)) -> list[tuple[str, str]]:
    """(planner, preset) pairs to run. A planner whose paper preset changes nothing (APF: eq. 2
    as written) runs once, as ``default``: both presets would give the same run."""
    from nodes.planner.registry import preset_settings

    out = []
    for planner in planners:
        for preset in presets:
            if preset != "default" and not preset_settings(planner, preset):
                preset = "default"
            if (planner, preset) not in out:
                out.append((planner, preset))
    return out


def run_offline(world: World | str, planner: str, seed: int = 0, timeout_s: float = 300.0,
                params=None, preset: str = "default") -> Trial:
    """One offline run (:func:`papf.offline.run.simulate`) with the planner's ``preset``."""
    from nodes.planner.registry import preset_sets
    from papf.offline.plan import param_sets
    from papf.offline.run import simulate  # pybullet: only for offline runs

    t0 = time.monotonic()
    r = simulate(world, planner, params=[*preset_sets(preset), *param_sets(params)], seed=seed,
                 max_time_s=timeout_s)
    return Trial(r.world, planner, seed, "offline", r.outcome, r.duration_s, r.length_m,
                 r.collisions, r.reason, min_clearance_m=r.min_clearance_m,
                 wall_time_s=time.monotonic() - t0, path=r.path, preset=preset)


# [s wall] an experiment's stack runs wait this long for each command (papf run's 2 s): its
# runs share the cores with each other (--workers) and with whatever else runs, and a command
# held past the wait would let the physics run on without it and change a figure.
LOCKSTEP_TIMEOUT_S = 10.0


def run_stack(world_file: str | Path, planner: str, seed: int = 0, timeout_s: float = 300.0,
              record: str | Path | None = None, planner_args: Sequence[str] = (),
              objects: str | None = None, namespace: str = "rosbot",
              startup_timeout_s: float = 60.0, preset: str = "default") -> Trial:
    """One run of the whole process stack on a free port; the path from the recording if any."""
    from nodes.planner.registry import preset_sets
    from papf.launch.run import RunConfig, run  # zenoh: only for stack runs

    planner_args = [*(a for kv in preset_sets(preset) for a in ("--set", kv)), *planner_args]
    if record is not None:
        Path(record).parent.mkdir(parents=True, exist_ok=True)
        Path(record).unlink(missing_ok=True)
    cfg = RunConfig(world=str(world_file), planner=planner, seed=seed, timeout_s=timeout_s,
                    record=str(record) if record else None, port=run_port(), progress=False,
                    planner_args=list(planner_args), objects=objects, namespace=namespace,
                    startup_timeout_s=startup_timeout_s, lockstep_timeout_s=LOCKSTEP_TIMEOUT_S)
    res = run(cfg)
    path = pose_path(record) if record is not None and Path(record).exists() else np.zeros((0, 2))
    return Trial(res.world, planner, seed, "stack", res.outcome, res.duration_s, res.path_length_m,
                 res.collisions, res.reason, charge_mAh=res.charge_mAh,
                 wall_time_s=res.wall_time_s, path=path, preset=preset)


@dataclass(frozen=True)
class TrialJob:
    """One run of a sweep, self-contained so any machine of a Dask cluster can make it."""

    world: World                    # offline runs use it as is
    world_file: str                 # stack runs: the world file's name and text (the nodes
    world_text: str                 # load it on the machine that runs them)
    planner: str
    seed: int
    mode: str                       # offline | stack
    timeout_s: float = 300.0
    sets: tuple[str, ...] = ()      # name=value planner settings
    record: bool = False            # stack: record it and send the file back
    index: int = 0                  # position in the sweep (its key namespace)
    preset: str = "default"         # planner preset

    @property
    def label(self) -> str:
        """``WORLD PLANNER (PRESET) seed N``."""
        return f"{self.world.name} {variant_label(self.planner, self.preset)} seed {self.seed}"


def trial_job(world: World, world_file: str | Path, text: str | None = None, **kw) -> TrialJob:
    """A job for ``world`` whose file is ``world_file`` (its text read unless given)."""
    return TrialJob(world, Path(world_file).name,
                    Path(world_file).read_text(encoding="utf-8") if text is None else text, **kw)


def run_job(job: TrialJob) -> tuple[Trial, bytes | None]:
    """Make one sweep run: (the trial, the recording's bytes when ``job.record``)."""
    import tempfile

    from papf.experiments.sweep import run_namespace

    if job.mode == "offline":
        return run_offline(job.world, job.planner, job.seed, job.timeout_s, list(job.sets),
                           preset=job.preset), None
    with tempfile.TemporaryDirectory(prefix="papf-sweep-") as tmp:
        file = Path(tmp) / job.world_file
        replace_text(file, job.world_text, encoding="utf-8")
        rec = Path(tmp) / "run.mcap" if job.record else None
        trial = run_stack(file, job.planner, job.seed, job.timeout_s, record=rec,
                          planner_args=[a for kv in job.sets for a in ("--set", kv)],
                          namespace=run_namespace(job.index), preset=job.preset)
        return trial, (rec.read_bytes() if rec is not None and rec.exists() else None)


def trials_from_csv(path: str | Path) -> list[Trial]:
    """The trials of an experiment's per-run CSV (no paths): to rebuild its tables."""
    def num(x):
        return float(x) if x not in ("", None) else math.nan

    with Path(path).open(newline="") as fh:
        return [Trial(r["world"], r["planner"], int(r["seed"]), r["mode"], r["outcome"],
                      num(r["duration_s"]), num(r["path_length_m"]), int(r["collisions"]),
                      r.get("reason", ""), num(r.get("min_clearance_m")), num(r.get("charge_mAh")),
                      num(r.get("wall_time_s")), preset=r.get("preset") or "default")
                for r in csv.DictReader(fh)]


def pose_path(mcap: str | Path, namespace: str = "*") -> np.ndarray:
    """(N, 2) ground-truth positions [m] from a recording's ``<ns>/sim/pose`` channel."""
    from papf.recording.reader import iter_messages  # mcap: only with a recording

    pts = []
    try:
        for _key, msg, _t in iter_messages(mcap, keys=f"{namespace}/sim/pose"):
            if hasattr(msg, "x"):
                pts.append((msg.x, msg.y))
    except RecordingError as exc:
        logging.getLogger("papf.experiment").warning("no path from %s: %s", mcap, exc)
    return np.array(pts, dtype=float).reshape(-1, 2)


def load_all(names: Sequence[str]) -> list[World]:
    """Load each world of ``names``."""
    return [load_world(n) for n in names]


def write_csv(rows: list[dict], path: str | Path) -> Path:
    """Write ``rows`` as CSV (header from the first row) to ``path``; the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with output(path, force=True) as tmp, tmp.open("w", newline="") as fh:
        if rows:
            w = csv.DictWriter(fh, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)
    return path


def markdown_table(header: Sequence[str], rows: Sequence[Sequence[object]]) -> str:
    """A GitHub-flavoured Markdown table."""
    def cell(x):
        return str(x).replace("|", "\\|")

    out = ["| " + " | ".join(map(cell, header)) + " |", "|" + "---|" * len(header)]
    out += ["| " + " | ".join(map(cell, r)) + " |" for r in rows]
    return "\n".join(out) + "\n"


def progress_bar(enabled: bool | None = None) -> Progress:
    """A rich progress bar on stderr (``enabled=None``: when stderr is a terminal)."""
    console = Console(stderr=True)
    return Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
                    TimeElapsedColumn(), console=console,
                    disable=not (console.is_terminal if enabled is None else enabled))


def trial_line(t: Trial) -> str:
    """One line per finished trial (printed in a terminal and when piped alike)."""
    extra = f"  {t.charge_mAh:7.2f} mAh" if math.isfinite(t.charge_mAh) else ""
    return (f"{t.world:>16} {t.label:<6} seed {t.seed:<3} {t.outcome:<9} "
            f"{t.duration_s:7.2f} s  {t.path_length_m:6.2f} m{extra}  wall {t.wall_time_s:5.1f} s"
            + (f"  {t.reason}" if t.outcome != "reached" and t.reason else ""))


def quiet_runner_logs() -> None:
    """The launcher logs a line per 10 s of sim time when it has no progress bar: mute those."""
    logging.getLogger("papf.run").setLevel(logging.WARNING)


def sweep_trials(jobs: Sequence[TrialJob], sweep: SweepOptions | None, progress: bool | None,
                 title: str, out: Path) -> list[Trial]:
    """Run the jobs (in order, on the sweep's engine) and keep their recordings under ``out``.

    A recording is made where its run ran and comes back as bytes; it is written here as
    ``out/recordings/<world>-<planner>[-<preset>].mcap``.
    """
    opts = dataclasses.replace(sweep or SweepOptions(), progress=progress)
    journal = Journal(out)
    kept = {i: t for i, t in ((i, _resumed(journal, job)) for i, job in enumerate(jobs)) if t}
    if kept:
        print(f"{title}: {len(kept)} of {len(jobs)} runs finished before, taken from "
              f"{journal.dir} (delete it to make them again)", file=sys.stderr)

    def finished(job: TrialJob, result) -> None:   # on disk the moment the run ends
        trial, data = result
        if data is not None:
            rec = out / "recordings" / f"{_stem(job)}.mcap"
            rec.parent.mkdir(parents=True, exist_ok=True)
            with output(rec, force=True) as tmp:
                tmp.write_bytes(data)
        journal.put(_job_key(job), _trial_data(trial))

    todo = [job for i, job in enumerate(jobs) if i not in kept]
    done = iter(map_runs(run_job, todo, opts, label=lambda j: j.label, title=title,
                         line=lambda _j, r: trial_line(r[0]), on_done=finished))
    return [kept[i] if i in kept else next(done)[0] for i in range(len(jobs))]


def _stem(job: TrialJob) -> str:
    return job.world.name + "-" + job.planner + ("" if job.preset == "default" else "-" + job.preset)


def _job_key(job: TrialJob) -> str:
    return run_key(job.world, job.world_text, job.planner, job.seed, job.mode, job.timeout_s,
                   job.sets, job.record, job.preset)


def _trial_data(trial: Trial) -> dict:
    d = {f.name: getattr(trial, f.name) for f in dataclasses.fields(trial) if f.name != "path"}
    d = {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in d.items()}
    return {**d, "path": np.asarray(trial.path, dtype=float).tolist()}


def _resumed(journal: Journal, job: TrialJob) -> Trial | None:
    """The Trial of a finished run of ``job``, or None (not finished, or its entry is not
    a Trial: the run is made again)."""
    data = journal.get(_job_key(job))
    if data is None:
        return None
    try:
        fields = {f.name for f in dataclasses.fields(Trial)} - {"path"}
        kw = {k: (math.nan if v is None else v) for k, v in data.items() if k in fields}
        path = np.asarray(data.get("path") or np.zeros((0, 2)), dtype=float)
        if path.ndim != 2 or path.shape[1] not in (2, 3):
            return None
        return Trial(**kw, path=path)
    except (TypeError, ValueError):
        return None
