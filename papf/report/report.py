"""``papf report``: the energy report of recorded runs, from the MCAP files alone.

``build_report(["DIR"], out="DIR")`` reads every ``*.mcap`` (per-run figures:
:mod:`papf.report.metrics`), then writes ``report.md`` (tables with the figures beside
them), ``report.csv`` (runs, then per-planner mean and sd) and three PNGs. Nothing in it
depends on the wall clock or the order files are listed in, so running it again on the
same files gives the same files.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from common.errors import ConfigError, PapfError, RecordingError
from papf.mind_plots import mind_png
from papf.report import figures, tables
from papf.report.metrics import OSCILLATION_W_RAD_S, RunMetrics, run_metrics
from worlds import World, load_world

REPORT_MD = "report.md"
REPORT_CSV = "report.csv"
TRAJECTORIES_PNG = "trajectories.png"
CHARGE_PNG = "charge.png"
MOTION_PNG = "motion.png"
MIND_PNG = "mind.png"


@dataclass
class Report:
    runs: list[RunMetrics]
    summaries: list[tables.PlannerSummary]
    out_dir: Path
    files: list[Path] = field(default_factory=list)   # what was written

    def summary(self, planner: str) -> tables.PlannerSummary | None:
        return next((s for s in self.summaries if s.planner == planner), None)


def find_recordings(inputs: Iterable[str | Path]) -> list[Path]:
    """The ``.mcap`` files named, and those directly inside named directories (sorted)."""
    found: list[Path] = []
    for item in inputs:
        p = Path(item)
        if p.is_dir():
            found += sorted(f for f in p.glob("*.mcap") if f.is_file())
        elif p.is_file():
            found.append(p)
        else:
            raise RecordingError(f"{str(item)!r}: no such file or directory")
    if not found:
        raise RecordingError("no .mcap recordings in " + ", ".join(map(str, inputs)))
    return list(dict.fromkeys(found))


def default_out(inputs: Sequence[str | Path]) -> Path:
    """The one directory given, else the directory of the first file."""
    first = Path(inputs[0])
    return first if len(inputs) == 1 and first.is_dir() else first.parent


def collect(paths: Sequence[Path], energy_model: str | None = None,
            energy_params: dict | None = None) -> list[RunMetrics]:
    """Per-run figures, ordered by planner (apf, papf, ...), seed, file name."""
    runs = [run_metrics(p, energy_model, energy_params) for p in paths]
    order = tables.planner_order([r.planner for r in runs])
    return sorted(runs, key=lambda r: (order.index(r.planner), r.seed, r.file))


def build_report(inputs: Sequence[str | Path], out_dir: str | Path | None = None,
                 energy_model: str | None = None, energy_params: dict | None = None) -> Report:
    """Read the recordings, write report.md, report.csv and the PNGs into ``out_dir``."""
    if energy_model not in (None, "paper", "motor"):
        raise ConfigError(f"energy model {energy_model!r} is not one of paper, motor")
    paths = find_recordings(inputs)
    runs = collect(paths, energy_model, energy_params)
    out = Path(out_dir) if out_dir is not None else default_out(inputs)
    out.mkdir(parents=True, exist_ok=True)
    summaries = tables.summarise(runs)
    report = Report(runs, summaries, out)
    world = _world(runs)
    report.files += [figures.trajectories_png(runs, world, out / TRAJECTORIES_PNG),
                     figures.charge_png(runs, summaries, out / CHARGE_PNG),
                     figures.motion_png(runs, out / MOTION_PNG),
                     mind_png(runs, {Path(p).name: Path(p) for p in paths}, world,
                              out / MIND_PNG)]
    tables.write_csv(out / REPORT_CSV, runs, summaries)
    (out / REPORT_MD).write_text(markdown(report))
    report.files += [out / REPORT_CSV, out / REPORT_MD]
    return report


def _world(runs: Sequence[RunMetrics]) -> World | None:
    names = {r.world for r in runs}
    try:
        return load_world(sorted(names)[0]) if len(names) == 1 else None
    except PapfError:  # a world file that moved since the run: plot the paths alone
        return None


def _models(runs: Sequence[RunMetrics]) -> str:
    used = sorted({r.energy_model for r in runs})
    live = sorted({r.live_model for r in runs if r.live_model})
    text = f"re-metered with the **{', '.join(used)}** model"
    return text + (f" (the live meter ran: {', '.join(live)})" if live else "")


def _headline(report: Report) -> str:
    apf, papf = report.summary("apf"), report.summary("papf")
    if apf is None or papf is None:
        return ""
    a, p = apf.stats["charge_mAh"], papf.stats["charge_mAh"]
    pct = tables.change_pct(a, p)
    if pct != pct:  # nan: a planner has no completed run
        return ("**PAPF vs APF:** no comparison (a planner has no run that reached the goal).\n")
    verdict = "lower" if pct < 0 else "higher"
    return (f"**PAPF vs APF:** mean charge {p.mean:.2f} vs {a.mean:.2f} mAh — PAPF draws "
            f"{abs(pct):.1f} % {verdict} (paper: {tables.PAPER_CHARGE_MAH['papf']} vs "
            f"{tables.PAPER_CHARGE_MAH['apf']} mAh, {tables.PAPER_CHARGE_CHANGE_PCT:+.1f} %).\n")


def markdown(report: Report) -> str:
    runs = report.runs
    worlds = ", ".join(sorted({r.world for r in runs}))
    return "\n".join([
        "# Energy report",
        "",
        f"{len(runs)} recorded runs on world `{worlds}`; charge and energy {_models(runs)}. "
        "Every figure comes from the MCAP files alone (`papf report`); definitions: "
        "docs/experiments-energy.md.",
        "",
        _headline(report),
        "## Per planner (runs that reached the goal: mean ± sd)",
        "",
        tables.summary_markdown(report.summaries),
        "",
        f"![charge per run]({CHARGE_PNG})",
        "",
        "## Comparison with the paper",
        "",
        tables.comparison_markdown(report.summaries),
        "",
        "The paper's absolute charge (a real ROSbot, its own track, the charger's reading) is not "
        "comparable with a simulated run's; the relative change is.",
        "",
        "## Runs",
        "",
        tables.runs_markdown(runs),
        "",
        "duration: first motion (|v| > 0.01 m/s) to the outcome; path: ground-truth pose up to "
        "the outcome; mean P: energy / outcome time; ∫β² dt [rad²/s³] and ∫j² dt [m²/s⁵]: "
        "squared angular acceleration and linear jerk of the odometry over the motion; osc.: "
        f"sign changes of ω beyond ±{OSCILLATION_W_RAD_S} rad/s; live charge: the live meter's "
        "last recorded figure at or before the outcome; re-meter Δ: re-metered minus live "
        "charge at that stamp (0 = the live meter is reproduced exactly).",
        "",
        f"![trajectories]({TRAJECTORIES_PNG})",
        "",
        "## Motion (like the paper's Fig. 13)",
        "",
        f"![heading, v and ω over time]({MOTION_PNG})",
        "",
        f"![the planner's mind: prediction, abandoned predictions, top quarks, temporary goal, "
        f"footprints]({MIND_PNG})",
        "",
    ])
