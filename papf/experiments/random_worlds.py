"""``papf experiment random``: success and collision rates of each planner on random worlds.

The first ``n`` solvable worlds of a seeded set (:mod:`papf.offline.world_gen`) with every
planner at its defaults, offline or through the stack; writes ``OUT/random.md``, ``.csv``
and the worlds. Details: :func:`run_random`.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from common.errors import ConfigError
from common.outfiles import replace_text
from nodes.planner.registry import with_role
from papf.experiments.sweep import SweepOptions
from papf.experiments.trials import (
    markdown_table,
    quiet_runner_logs,
    sweep_trials,
    trial_job,
    variants,
    write_csv,
)
from papf.offline.world_gen import KINDS, bottleneck_width, generate_solvable, world_to_toml

OUTCOMES = ("reached", "collision", "stagnated", "timeout", "failed")
WIDE_M = 0.9   # [m] bottleneck from which APF-family fields (d_o = 0.5 m) pass (docs/experiments.md)
DEFAULT_PLANNERS = with_role("compared")   # the planners that declare they are compared


def kind_of(world_name: str) -> str:
    """``rand-<seed>-<index>-<kind>`` -> kind."""
    return world_name.split("-", 3)[-1]


def _rate(trials) -> float:
    return 100.0 * sum(t.outcome == "reached" for t in trials) / len(trials) if trials else float("nan")


def summarize(trials, bottleneck: dict[str, float] | None = None) -> list[dict]:
    """Per planner: worlds, rate of each outcome [%], success rate per kind and, given the
    worlds' bottleneck widths, on the worlds whose bottleneck is >= / < WIDE_M [%]."""

    bottleneck = bottleneck or {}
    rows = []
    for planner in dict.fromkeys(t.label for t in trials):
        mine = [t for t in trials if t.label == planner]
        row = {"planner": planner, "worlds": len(mine)}
        for o in OUTCOMES:
            row[o] = 100.0 * sum(t.outcome == o for t in mine) / len(mine)
        row["collisions"] = sum(t.collisions for t in mine)
        for k in KINDS:
            row[f"reached_{k}"] = _rate([t for t in mine if kind_of(t.world) == k])
        wide = [t for t in mine if bottleneck.get(t.world, 0.0) >= WIDE_M]
        narrow = [t for t in mine if t.world in bottleneck and bottleneck[t.world] < WIDE_M]
        row["wide_worlds"], row["reached_wide"] = len(wide), _rate(wide)
        row["narrow_worlds"], row["reached_narrow"] = len(narrow), _rate(narrow)
        rows.append(row)
    return rows


def summary_markdown(summary: list[dict], n: int, seed: int, mode: str, rejected: int) -> str:

    """The random-worlds table (Markdown): outcomes [%] per planner, by kind and width."""
    header = ["planner", "worlds", *[f"{o} [%]" for o in OUTCOMES], "collisions",
              *[f"reached: {k} [%]" for k in KINDS],
              f"reached: bottleneck >= {WIDE_M} m [%]", f"reached: bottleneck < {WIDE_M} m [%]"]
    rows = [[r["planner"], r["worlds"], *[f"{r[o]:.1f}" for o in OUTCOMES], r["collisions"],
             *[f"{r[f'reached_{k}']:.1f}" for k in KINDS],
             f"{r['reached_wide']:.1f} (of {r['wide_worlds']})",
             f"{r['reached_narrow']:.1f} (of {r['narrow_worlds']})"] for r in summary]
    return (f"# Random worlds ({mode}, set {seed}: {n} solvable worlds, {rejected} unsolvable "
            "ones skipped)\n\n" + markdown_table(header, rows))


def run_random(out: str | Path, n: int = 50, seed: int = 0,
               planners: Sequence[str] = DEFAULT_PLANNERS, mode: str = "offline",
               timeout_s: float = 300.0, plots: bool = False, progress: bool | None = None,
               sets: Sequence[str] = (), sweep: SweepOptions | None = None,
               presets: Sequence[str] = ("default",)):
    """Run the experiment; write its files into ``out``; return (trials, summary rows).

    ``sets``: ``name=value`` planner settings applied to every planner (as ``--set``);
    ``sweep``: how the runs are spread (:mod:`papf.experiments.sweep`; default one by one);
    ``presets``: planner presets side by side (:func:`papf.experiments.trials.variants`).

    The first ``n`` *solvable* worlds of the seeded set (:func:`papf.offline.world_gen.generate_solvable`:
    obstacle fields, dead ends, narrow gaps, in turn) are run with every planner — offline by
    default (:func:`papf.offline.run.simulate`, fast), or through the whole stack (``mode="stack"``). Writes

    - ``OUT/random.md`` — per planner: reached / collision / stagnated / timeout / failed rates
      over the solvable worlds, the success rate per world kind, and split by the world's
      bottleneck (:func:`papf.offline.world_gen.bottleneck_width`) at :data:`WIDE_M`;
    - ``OUT/random.csv`` — one row per run;
    - ``OUT/worlds/<name>.toml`` — every world (so a run can be repeated with ``papf plan`` or
      ``papf run``), and with ``plots=True`` ``OUT/plots/<name>.png`` (all planners' paths).

    The planners' parameters are their defaults: nothing is tuned to these worlds.
    """
    from papf.plots.paths import plot_paths  # matplotlib: only when the experiment runs

    if mode not in ("stack", "offline"):
        raise ConfigError(f"mode {mode!r} is not stack or offline")
    if n < 1:
        raise ConfigError(f"--n {n}: need at least 1 world")
    out = Path(out)
    (out / "worlds").mkdir(parents=True, exist_ok=True)
    quiet_runner_logs()
    worlds, rejected = generate_solvable(n, seed)
    bottleneck = {w.name: bottleneck_width(w) for w in worlds}
    runs = variants(planners, presets)
    jobs = []
    for world in worlds:
        file = out / "worlds" / f"{world.name}.toml"
        replace_text(file, world_to_toml(world))
        jobs += [trial_job(world, file, planner=planner, seed=seed, mode=mode, timeout_s=timeout_s,
                           sets=tuple(sets), record=plots and mode == "stack", index=len(jobs) + k,
                           preset=preset)
                 for k, (planner, preset) in enumerate(runs)]
    trials = sweep_trials(jobs, sweep, progress, "random worlds", out)
    if plots:
        for world in worlds:
            mine = [t for t in trials if t.world == world.name]
            plot_paths(world, {f"{t.label} ({t.outcome})": t.path for t in mine},
                       out / "plots" / f"{world.name}.png", world.name)
    summary = summarize(trials, bottleneck)
    write_csv([{**t.row(), "bottleneck_m": round(bottleneck[t.world], 3)} for t in trials],
              out / "random.csv")
    replace_text((out / "random.md"), summary_markdown(summary, len(worlds), seed, mode, rejected))
    write_summary_csv(summary, out / "random-summary.csv")
    return trials, summary


def write_summary_csv(summary: list[dict], path: Path) -> None:
    """The summary rows (rates rounded to 0.1 %), the CSV of ``random.md``'s table."""
    write_csv([{k: (round(v, 1) if isinstance(v, float) else v) for k, v in r.items()}
               for r in summary], path)


def rebuild_summary(out: str | Path) -> list[dict]:
    """``random-summary.csv`` from ``random.csv`` (per-run rows with ``bottleneck_m``)."""
    import csv

    from papf.experiments.trials import trials_from_csv

    out = Path(out)
    trials = trials_from_csv(out / "random.csv")
    with (out / "random.csv").open(newline="") as fh:
        bottleneck = {r["world"]: float(r["bottleneck_m"]) for r in csv.DictReader(fh)}
    summary = summarize(trials, bottleneck)
    write_summary_csv(summary, out / "random-summary.csv")
    return summary
