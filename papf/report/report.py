"""``papf report``: the energy report of recorded runs, from the MCAP files alone.

``build_report(["DIR"], out="DIR")`` reads every ``*.mcap`` (per-run figures:
:mod:`papf.report.metrics`), then writes ``report.md`` (tables with the figures beside
them), ``report.csv`` (runs, then per world and planner mean and sd), the PNGs and
``report.html`` (report.md with the PNGs embedded: one file a browser opens).

- **Energy model**: charge and energy come from the model the live meter ran (the run
  metadata, else the recorded battery messages), unless ``energy_model`` says otherwise;
  every table header and figure names the model. A report re-metered with another model
  than the live one goes to its own files (``report-paper.md``, ``charge-paper.png``, …), so
  it never overwrites the as-run report.
- **Worlds**: runs of different worlds are grouped per world — a section, a statistics
  row per planner, a trajectory and a motion figure each — and never averaged together.
- **Pose source**: trajectories and path lengths come from the ground truth
  (``sim/pose``) in simulation and from odometry on a real robot; the report says which.

Nothing depends on the wall clock or the order files are listed in, so running it again
on the same files gives the same files.
"""

from __future__ import annotations

import os
import re
import shutil
import tempfile
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from common.errors import ConfigError, PapfError, RecordingError
from common.outfiles import OutputError, check_output
from papf.plots.moment import MomentPanel, moment_png
from papf.recording.rosbag import TopicMap, is_rosbag
from papf.report import figures, sides, tables
from papf.report.html import report_html
from papf.report.markdown import markdown
from papf.report.metrics import BAG, RunMetrics, fleet_namespaces, run_facts, run_metrics, seed_text
from worlds import World, load_world

MODELS = ("paper", "motor")
POSE_TEXT = {"sim/pose": "ground truth (sim/pose)",
             "odom": "odometry (odom: a real robot has no ground truth)"}


@dataclass
class Report:
    runs: list[RunMetrics]
    summaries: list[tables.PlannerSummary]
    out_dir: Path
    files: list[Path] = field(default_factory=list)   # what was written
    suffix: str = ""                                  # "-<model>" for a re-metered report
    pngs: dict = field(default_factory=dict)          # (kind, world) -> file name

    def summary(self, planner: str, world: str | None = None) -> tables.PlannerSummary | None:
        return next((s for s in self.summaries if s.planner == planner
                     and (world is None or s.world == world)), None)

    @property
    def model(self) -> str:
        return ", ".join(sorted({r.energy_model for r in self.runs}))

    @property
    def live_models(self) -> str:
        return ", ".join(sorted({r.live_model for r in self.runs if r.live_model}))

    @property
    def model_note(self) -> str:
        live = self.live_models
        if not self.suffix and not live:   # rosbag2s: the robot's own meter is not in them
            return f"energy model: {self.model} (re-metered; no live meter recorded)"
        if not self.suffix:
            return f"energy model: {self.model} (as the live meter ran)"
        return f"energy model: {self.model} (re-metered; the live meter ran {live or 'none'})"

    @property
    def pose_note(self) -> str:
        return "pose: " + "; ".join(POSE_TEXT.get(p, p) for p in
                                    sorted({r.pose_source for r in self.runs}))

    def name(self, stem: str, world: str | None = None, ext: str = ".png") -> str:
        """``stem[-world][-model]ext``: the world only when the report covers several."""
        return file_name(stem, world, ext, len(tables.worlds_of(self.runs)) > 1, self.suffix)


def file_name(stem: str, world: str | None, ext: str, several: bool, suffix: str) -> str:
    """A report file's name: ``stem[-world][-model]ext``, the world only when ``several``."""
    w = f"-{re.sub(r'[^A-Za-z0-9_.-]+', '_', Path(world).stem)}" if world and several else ""
    return f"{stem}{w}{suffix}{ext}"


def report_files(worlds: Sequence[str], suffix: str) -> list[str]:
    """Every file a report of runs of ``worlds`` writes (the order :func:`_write` makes them)."""
    several = len(set(worlds)) > 1
    names = [file_name("charge", None, ".png", several, suffix)]
    for world in sorted(set(worlds)):
        names += [file_name(stem, world, ".png", several, suffix)
                  for stem in ("trajectories", "motion", "mind")]
    return names + [file_name("report", None, ext, several, suffix)
                    for ext in (".csv", ".md", ".html")]


def check_outputs(paths: Sequence[Path], out: Path, energy_model: str | None,
                  topics: TopicMap | None, force: bool) -> None:
    """Refuse an existing report file (without ``force``) or an input as output before
    anything is computed: the names come from the recordings' metadata alone
    (:func:`papf.report.metrics.run_facts`)."""
    facts = [run_facts(p, topics) for p in paths]
    live = {model for _w, model in facts if model}
    suffix = "" if energy_model is None or live == {energy_model} else f"-{energy_model}"
    names = report_files([w for w, _m in facts], suffix)
    for name in names:
        check_output(out / name, paths, force=True)   # an input, a directory: refused anyway
    there = [n for n in names if os.path.lexists(out / n)]
    if there and not force:
        where = "this directory" if str(out) == "." else str(out)
        raise OutputError(f"{where} already holds a report ({', '.join(there)}); use --force to "
                          "replace it, or --out DIR to write it elsewhere")


def find_recordings(inputs: Iterable[str | Path]) -> list[Path]:
    """The ``.mcap`` files and rosbag2 directories named, and those directly inside named
    directories (sorted)."""
    found: list[Path] = []
    for item in inputs:
        p = Path(item)
        if p.is_dir() and is_rosbag(p):
            found.append(p)
        elif p.is_dir():
            found += sorted(f for f in p.iterdir() if (f.is_file() and f.suffix == ".mcap")
                            or (f.is_dir() and is_rosbag(f)))
        elif p.is_file():
            found.append(p)
        elif p.exists():
            raise RecordingError(f"{str(item)!r} is not a regular file (a FIFO or device); "
                                 "give .mcap files or directories")
        else:
            raise RecordingError(f"{str(item)!r}: no such file or directory")
    if not found:
        raise RecordingError("no .mcap recordings or rosbag2 directories in "
                             + ", ".join(map(str, inputs)))
    return list(dict.fromkeys(found))


def default_out(inputs: Sequence[str | Path]) -> Path:
    """The one directory given (beside it for a rosbag2: never inside the robot's bag),
    else the directory of the first file."""
    first = Path(inputs[0])
    if len(inputs) == 1 and first.is_dir():
        return first.parent / f"{first.name}-report" if is_rosbag(first) else first
    return first.parent


def collect(paths: Sequence[Path], energy_model: str | None = None,
            energy_params: dict | None = None, topics: TopicMap | None = None,
            progress=None) -> list[RunMetrics]:
    """Per-run figures, ordered by world, planner (apf, papf, ...), seed, file name.
    ``progress``: a :class:`papf.console.progress.StepProgress` told of each file, or None."""
    runs, robot_sides = [], []
    for p in paths:
        if progress is not None:
            progress.doing(f"reading {Path(p).name}")
        if sides.is_robot_side(Path(p), topics):   # a robot's black box: after the laptops'
            robot_sides.append(Path(p))
        else:
            runs += [run_metrics(p, energy_model, energy_params, topics=topics, robot=robot)
                     for robot in (fleet_namespaces(p, topics) or [None])]   # a fleet: each robot
        if progress is not None:
            progress.step(f"read {Path(p).name}")
    by_name = {Path(p).name: Path(p) for p in paths}
    for box in robot_sides:
        runs = with_robot_side(runs, box, by_name, energy_model, energy_params)
    order = tables.planner_order([r.planner for r in runs])
    return sorted(runs, key=lambda r: (r.world, order.index(r.planner), r.seed, r.file))


def with_robot_side(runs: list[RunMetrics], box: Path, files: dict, energy_model: str | None,
                    energy_params: dict | None) -> list[RunMetrics]:
    """``runs`` with each laptop run the robot's black box ``box`` also holds paired with it
    (:func:`papf.report.sides.pair`), and the box's other runs added on their own."""
    segs = sides.segments(box)
    free = list(segs)
    out = []
    for m in runs:
        path = files.get(m.file)
        seg = (sides.match(sides.run_ended_detail(path), free)
               if path is not None and not m.robot and m.outcome != BAG and m.sides is None else None)
        if seg is None:
            out.append(m)
            continue
        free.remove(seg)
        robot = run_metrics(box, energy_model or m.energy_model, energy_params, window=seg)
        ns = f"{robot_namespace(box)}"
        gaps = sides.missed(sides.odom_stamps(path, ns), sides.odom_stamps(box, ns, seg),
                            int(round(m.t_end_s * 1e9)))
        out.append(sides.pair(m, robot, gaps, box.name))
    for seg in free:   # runs only the robot recorded (or a robot recording given alone)
        alone = run_metrics(box, energy_model, energy_params, window=seg)
        alone.file = box.name if len(segs) == 1 else f"{box.name}#{seg.index + 1}"
        ran = sides.result_of(seg.ended)   # what the launcher said it ran (the robot's
        if alone.planner == "unknown":     # recorder has no planner in its metadata)
            alone.planner = str(ran.get("planner", alone.planner))
        if alone.seed < 0 and isinstance(ran.get("seed"), int):
            alone.seed = ran["seed"]
        out.append(alone)
    return out


def robot_namespace(path: Path) -> str:
    from papf.recording.reader import Recording

    with Recording(path) as rec:
        odom = [k for k in rec.keys() if k.endswith("/odom")]
        return rec.run_metadata.get("namespace") or (odom[0][: -len("/odom")] if odom else "rosbot")


def suffix_for(runs: Sequence[RunMetrics], energy_model: str | None) -> str:
    """"" when the figures use the live meter's model; "-<model>" for a re-metered report."""
    if energy_model is None:
        return ""
    live = {r.live_model for r in runs if r.live_model}
    return "" if live == {energy_model} else f"-{energy_model}"


def build_report(inputs: Sequence[str | Path], out_dir: str | Path | None = None,
                 energy_model: str | None = None, energy_params: dict | None = None,
                 topics: TopicMap | None = None, progress=None, force: bool = False) -> Report:
    """Read the recordings (and rosbag2s, their topics mapped by ``topics``), write
    report.md, report.csv and the PNGs into ``out_dir``. ``progress``: a
    :class:`papf.console.progress.StepProgress` (its total is set here: a step per file
    read and per figure drawn), or None.

    The one output rule (:mod:`common.outfiles`): the files are written into a staging
    directory and moved into ``out_dir`` only once all are written; a report file already
    there is replaced only with ``force``, a symlink is replaced (never followed), and a
    name that is one of the inputs (a hard link, a symlink to a recording) is refused even
    with ``force`` — checked for every file before the first one moves."""
    if energy_model not in (None, *MODELS):
        raise ConfigError(f"energy model {energy_model!r} is not one of {', '.join(MODELS)}")
    paths = find_recordings(inputs)
    out = Path(out_dir) if out_dir is not None else default_out(inputs)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise RecordingError(f"cannot create the report directory {str(out)!r}: "
                             f"{exc.strerror}") from None
    check_outputs(paths, out, energy_model, topics, force)   # before the work, not after it
    if progress is not None:
        progress.total = len(paths) + 2   # + the charge figure and the tables (worlds: later)
    runs = collect(paths, energy_model, energy_params, topics, progress)
    files = {Path(p).name: Path(p) for p in paths}
    report = Report(runs, tables.summarise(runs), out, suffix=suffix_for(runs, energy_model))
    stage = Path(tempfile.mkdtemp(prefix=".papf-report-", dir=out))
    try:   # into a staging directory, moved into out only once every file is written
        _write(report, runs, files, stage, topics, progress)
        for f in report.files:   # every name checked before the first file moves
            check_output(out / f.name, paths, force)
        report.files = [_move(f, out) for f in report.files]
    except OSError as exc:
        raise RecordingError(f"cannot write the report into {str(out)!r}: {exc.strerror}; "
                             "nothing was written") from None
    finally:
        shutil.rmtree(stage, ignore_errors=True)
    return report


def _move(path: Path, out: Path) -> Path:
    """A staged report file into ``out`` (checked: :func:`common.outfiles.check_output`)."""
    dst = out / path.name
    os.replace(path, dst)
    return dst


def _write(report: Report, runs: list, files: dict, out: Path,
           topics: TopicMap | None = None, progress=None) -> None:
    """The report's PNGs, CSV and Markdown into ``out``."""
    def doing(text: str) -> None:
        if progress is not None:
            progress.doing(text)

    def done(text: str) -> None:
        if progress is not None:
            progress.step(text)

    worlds = tables.worlds_of(runs)
    if progress is not None:
        progress.total += 3 * len(worlds)
    note = f"{report.model_note} · {report.pose_note} · papf report"
    charge = report.name("charge")
    doing(f"drawing {charge}")
    report.files.append(figures.charge_png(runs, report.summaries, out / charge, note,
                                           report.model))
    report.pngs[("charge", None)] = charge
    done(f"drew {charge}")
    pose = "; ".join(sorted({r.pose_source for r in runs}))
    for world_name in worlds:
        mine = [r for r in runs if r.world == world_name]
        traj, motion = report.name("trajectories", world_name), report.name("motion", world_name)
        doing(f"drawing {traj}")
        report.files.append(figures.trajectories_png(mine, _world(world_name), out / traj, note,
                                                     pose))
        done(f"drew {traj}")
        doing(f"drawing {motion}")
        report.files.append(figures.motion_png(mine, out / motion, note))
        done(f"drew {motion}")
        report.pngs[("trajectories", world_name)] = traj
        report.pngs[("motion", world_name)] = motion
        mind = report.name("mind", world_name)
        doing(f"drawing {mind}")
        report.files.append(mind_figure(mine, files, _world(world_name), out / mind, topics))
        report.pngs[("mind", world_name)] = mind
        done(f"drew {mind}")
    doing("writing the tables")
    csv_path, md_path = out / report.name("report", ext=".csv"), out / report.name("report", ext=".md")
    html_path = out / report.name("report", ext=".html")
    tables.write_csv(csv_path, runs, report.summaries)
    text = markdown(report)
    md_path.write_text(text)
    pngs = {name: out / name for name in report.pngs.values()}   # embedded: one file to open
    html_path.write_text(report_html(text, pngs, f"papf report: {', '.join(worlds)}"),
                         encoding="utf-8")
    report.files += [csv_path, md_path, html_path]
    done(f"wrote {md_path.name}, {csv_path.name}, {html_path.name}")


def mind_figure(runs: Sequence[RunMetrics], files: dict, world: World | None, out: Path,
                topics: TopicMap | None = None) -> Path:
    """``mind.png``: the first run of each planner at the moment its planner acted."""
    from papf.recording.track import load_track

    firsts: dict[str, RunMetrics] = {}
    for r in runs:
        firsts.setdefault(r.planner, r)
    panels = []
    for planner, r in firsts.items():
        name, _, robot = r.file.partition(":")   # a fleet's run: "<file>:<robot>"
        track = load_track(files[name], topics=topics, robot=robot or None)
        v = np.interp(track.t, track.v_t, track.v) if len(track.v_t) else np.zeros(len(track.t))
        panels.append(MomentPanel(f"{planner} seed {seed_text(r.seed)} ({r.outcome})",
                                  planner.split(" ")[0], track.t, track.xyyaw, v, track.states))
    return moment_png(panels, world, out)


def _world(name: str) -> World | None:
    try:
        return load_world(name)
    except PapfError:  # a world file that moved since the run: plot the paths alone
        return None
