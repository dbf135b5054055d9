"""``papf experiment random``: success and collision rates of each planner on random worlds.

The first ``n`` *solvable* worlds of the seeded set (:func:`papf.randworlds.generate_solvable`:
obstacle fields, dead ends, narrow gaps, in turn) are run with every planner — offline by
default (:mod:`papf.plan`, fast), or through the whole stack (``mode="stack"``). Writes

- ``OUT/random.md`` — per planner: reached / collision / stagnated / timeout / failed rates
  over the solvable worlds, and the success rate per world kind;
- ``OUT/random.csv`` — one row per run;
- ``OUT/worlds/<name>.toml`` — every world (so a run can be repeated with ``papf plan`` or
  ``papf run``), and with ``plots=True`` ``OUT/plots/<name>.png`` (all planners' paths).

The planners' parameters are their defaults: nothing is tuned to these worlds.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

OUTCOMES = ("reached", "collision", "stagnated", "timeout", "failed")
DEFAULT_PLANNERS = ("apf", "papf", "arapf", "wang")


def kind_of(world_name: str) -> str:
    """``rand-<seed>-<index>-<kind>`` -> kind."""
    return world_name.split("-", 3)[-1]


def summarize(trials) -> list[dict]:
    """Per planner: number of worlds, rate of each outcome [%], success rate per kind [%]."""
    from papf.randworlds import KINDS

    rows = []
    for planner in dict.fromkeys(t.planner for t in trials):
        mine = [t for t in trials if t.planner == planner]
        row = {"planner": planner, "worlds": len(mine)}
        for o in OUTCOMES:
            row[o] = 100.0 * sum(t.outcome == o for t in mine) / len(mine)
        row["collisions"] = sum(t.collisions for t in mine)
        for k in KINDS:
            of_kind = [t for t in mine if kind_of(t.world) == k]
            row[f"reached_{k}"] = (100.0 * sum(t.outcome == "reached" for t in of_kind) / len(of_kind)
                                   if of_kind else float("nan"))
        rows.append(row)
    return rows


def summary_markdown(summary: list[dict], n: int, seed: int, mode: str, rejected: int) -> str:
    from papf.experiments.trials import markdown_table
    from papf.randworlds import KINDS

    header = ["planner", "worlds", *[f"{o} [%]" for o in OUTCOMES], "collisions",
              *[f"reached: {k} [%]" for k in KINDS]]
    rows = [[r["planner"], r["worlds"], *[f"{r[o]:.1f}" for o in OUTCOMES], r["collisions"],
             *[f"{r[f'reached_{k}']:.1f}" for k in KINDS]] for r in summary]
    return (f"# Random worlds ({mode}, set {seed}: {n} solvable worlds, {rejected} unsolvable "
            "ones skipped)\n\n" + markdown_table(header, rows))


def run_random(out: str | Path, n: int = 50, seed: int = 0,
               planners: Sequence[str] = DEFAULT_PLANNERS, mode: str = "offline",
               timeout_s: float = 300.0, plots: bool = False, progress: bool | None = None):
    """Run the experiment; write its files into ``out``; return (trials, summary rows)."""
    from papf.errors import ConfigError
    from papf.experiments.trials import (
        progress_bar,
        quiet_runner_logs,
        run_offline,
        run_stack,
        write_csv,
    )
    from papf.plots import plot_paths
    from papf.randworlds import generate_solvable, world_to_toml

    if mode not in ("stack", "offline"):
        raise ConfigError(f"mode {mode!r} is not stack or offline")
    if n < 1:
        raise ConfigError(f"--n {n}: need at least 1 world")
    out = Path(out)
    (out / "worlds").mkdir(parents=True, exist_ok=True)
    quiet_runner_logs()
    worlds, rejected = generate_solvable(n, seed)
    trials = []
    with progress_bar(progress) as bar:
        task = bar.add_task("random worlds", total=len(worlds) * len(planners))
        for world in worlds:
            file = out / "worlds" / f"{world.name}.toml"
            file.write_text(world_to_toml(world))
            mine = []
            for planner in planners:
                bar.update(task, description=f"{world.name} {planner}")
                if mode == "offline":
                    trial = run_offline(world, planner, seed, timeout_s)
                else:
                    rec = out / "recordings" / f"{world.name}-{planner}.mcap" if plots else None
                    trial = run_stack(file, planner, seed, timeout_s, record=rec)
                mine.append(trial)
                bar.advance(task)
            trials += mine
            if plots:
                plot_paths(world, {f"{t.planner} ({t.outcome})": t.path for t in mine},
                           out / "plots" / f"{world.name}.png", world.name)
    summary = summarize(trials)
    write_csv([t.row() for t in trials], out / "random.csv")
    (out / "random.md").write_text(summary_markdown(summary, len(worlds), seed, mode, rejected))
    return trials, summary
