"""``papf experiment crowd``: planners x numbers of people x seeds in a hall, CrowdNav-style.

The scene of ``(people, seed)`` (:func:`crowd_scene`): a walled hall ``HALL_X`` x ``HALL_Y``;
the robot drives from (0, 0) to (8, 0) along its middle. ``people`` pedestrians (ORCA, radius
0.3 m) are drawn from ``numpy.random.default_rng([seed, people])``: each, in turn, is a
*walker along* the hall (start near one end, goal near the other: head-on or overtaking
traffic) or a *walker across* it (start near one long wall, goal near the other, at a random
x), with a preferred speed uniform in ``SPEED_M_S``; starts and goals keep
``CLEAR_M`` from each other and from the robot's start and goal. Each walks to its goal and
back, in a loop, so the hall stays as busy for the whole run. Every scene is written as a
world file (``OUT/worlds/``): ``papf plan --world OUT/worlds/crowd-N-S.toml`` repeats a run.

Each run is :func:`papf.offline.run.simulate` (offline, :mod:`papf.offline.crowd`), spread by
:func:`papf.experiments.sweep.map_runs` (``--workers`` / ``--scheduler``). Writes
``OUT/crowd.csv`` (a row per run), ``OUT/crowd-summary.csv`` and ``OUT/crowd.md`` (per
planner x people: success, collision, stagnation and timeout rates; time and path of the
successful runs; mean min separation, discomfort time (and its share of the run, first
motion to outcome, CrowdNav's discomfort frequency), intrusions and path irregularity — the
measures of :mod:`common.crowd_measures`) and ``OUT/crowd.png``.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from common.errors import ConfigError
from common.optional import tomllib
from common.outfiles import output, replace_text
from nodes.planner.registry import with_role
from papf.experiments.journal import Journal, run_key
from papf.experiments.sweep import SweepOptions, map_runs
from papf.experiments.trials import markdown_table, write_csv
from worlds import World, parse_world

DEFAULT_PLANNERS = with_role("traffic")   # the planners compared among moving obstacles
DEFAULT_PEOPLE = (0, 5, 10, 20)
HALL_X = (-1.5, 9.5)          # [m] the hall's walls along x
HALL_Y = (-3.0, 3.0)          # [m] along y
START, GOAL = (0.0, 0.0, 0.0), (8.0, 0.0)
SPEED_M_S = (0.5, 1.0)        # [m/s] preferred speeds drawn from
CLEAR_M = 0.7                 # [m] between the centres of drawn points and the robot's ends
MARGIN_M = 0.6                # [m] a person's start/goal from the walls
MAX_HALL_PEOPLE = 20          # [-] the strips hold this many at CLEAR_M for every seed tried (0-59)
OUTCOMES = ("reached", "collision", "stagnated", "timeout", "failed")


def _draw_point(rng, kind: str, end: int, taken: list) -> tuple[float, float]:
    """A start (end 0) or goal (end 1) of a walker ``along`` or ``across`` the hall."""
    (x0, x1), (y0, y1) = HALL_X, HALL_Y
    for _ in range(1000):
        if kind == "along":
            x = rng.uniform(x1 - MARGIN_M - 2.0, x1 - MARGIN_M) if end == 0 else \
                rng.uniform(x0 + MARGIN_M, x0 + MARGIN_M + 2.0)
            y = rng.uniform(y0 + MARGIN_M, y1 - MARGIN_M)
        else:
            x = rng.uniform(x0 + 2.0, x1 - 2.0)
            side = y0 + MARGIN_M if end == 0 else y1 - MARGIN_M
            y = side + rng.uniform(0.0, 1.2) * (1 if end == 0 else -1)
        if all(math.hypot(x - a, y - b) >= CLEAR_M for a, b in taken):
            return round(float(x), 3), round(float(y), 3)
    raise ConfigError(f"no room left in the hall for a walker {kind} it after "
                      f"{len(taken) // 2 - 1} people")


def crowd_scene(people: int, seed: int) -> tuple[World, str]:
    """The hall with ``people`` pedestrians of ``seed`` (module doc): (world, its TOML)."""
    if not 0 <= people <= MAX_HALL_PEOPLE:
        raise ConfigError(f"{people} people: the hall takes 0 to {MAX_HALL_PEOPLE}")
    rng = np.random.default_rng([seed, people])
    taken = [START[:2], GOAL]
    lines = []
    for k in range(people):
        kind = "along" if k % 2 == 0 else "across"
        flip = rng.random() < 0.5                     # which end or wall they start from
        a = _draw_point(rng, kind, 1 if flip else 0, taken)
        taken.append(a)
        b = _draw_point(rng, kind, 0 if flip else 1, taken)
        taken.append(b)
        speed = round(float(rng.uniform(*SPEED_M_S)), 3)
        lines += ["[[people]]", f"start = [{a[0]}, {a[1]}]",
                  f"waypoints = [[{b[0]}, {b[1]}], [{a[0]}, {a[1]}]]", "loop = true",
                  f"speed = {speed}"]
    (x0, x1), (y0, y1) = HALL_X, HALL_Y
    name = f"crowd-{people}-{seed}"
    head = [f'name = "{name}"',
            f'description = "a {x1 - x0:g} x {y1 - y0:g} m hall, {people} people walking back '
            f'and forth (papf experiment crowd, seed {seed})"',
            "[robot]", f"start = {list(START)}", "[goal]", f"position = {list(GOAL)}",
            "tolerance = 0.1"]
    for a, b in (((x0, y0), (x1, y0)), ((x0, y1), (x1, y1)), ((x0, y0), (x0, y1)),
                 ((x1, y0), (x1, y1))):
        head += ["[[obstacles]]", 'kind = "wall"', f"from = {list(a)}", f"to = {list(b)}",
                 "thickness = 0.1"]
    text = "\n".join(head + lines) + "\n"
    return parse_world(tomllib.loads(text), f"{name}.toml"), text


@dataclass(frozen=True)
class CrowdJob:
    """One run: ``planner`` on ``world`` (a hall scene of ``people``, or a packaged world)."""

    world: World
    planner: str
    people: int
    seed: int
    timeout_s: float = 300.0
    sets: tuple[str, ...] = ()
    world_text: str = ""       # the world's TOML: what defines the run (its journal key)

    @property
    def key(self) -> str:
        """The run's journal key (:func:`papf.experiments.journal.run_key`)."""
        return run_key("crowd", self.world.name, self.world_text, self.planner, self.people,
                       self.seed, self.timeout_s, self.sets)


def run_crowd_job(job: CrowdJob) -> list[dict]:
    """One offline run -> a CSV row per robot (no wall time: rows depend on the run alone)."""
    from papf.offline.crowd import plan_crowd  # also with 0 people: the crowd measures

    res = plan_crowd(job.world, job.planner, list(job.sets), None, job.seed, job.timeout_s, 0.1)
    return [{"world": job.world.name, "robot": r["name"], "planner": r["planner"],
             "people": job.people, "seed": job.seed,
             "outcome": r["outcome"], "duration_s": round(r["duration_s"], 3),
             "path_length_m": round(r["path_length_m"], 3),
             "collisions_wall": r["collisions_wall"], "collisions_robot": r["collisions_robot"],
             "collisions_person": r["collisions_person"],
             "min_separation_m": "" if r["min_separation_m"] is None
             else round(r["min_separation_m"], 3),
             "discomfort_s": round(r["discomfort_s"], 3), "intrusions": r["intrusions"],
             "irregularity_rad_per_m": round(r["path_irregularity_rad_per_m"], 3)}
            for r in res.crowd["robots"]]


def _mean(values) -> float | str:
    vals = [float(v) for v in values if v != ""]
    return round(float(np.mean(vals)), 3) if vals else ""


def summarize(rows: list[dict], by: str = "people") -> list[dict]:
    """Per planner x ``by`` (people, or world): rates [%] over the robots' runs, the means
    (module doc)."""
    out = []
    for planner in dict.fromkeys(r["planner"] for r in rows):
        for group in dict.fromkeys(r[by] for r in rows):
            mine = [r for r in rows if r["planner"] == planner and r[by] == group]
            if not mine:
                continue
            ok = [r for r in mine if r["outcome"] == "reached"]
            row = {"planner": planner, by: group, "runs": len(mine)}
            for o in OUTCOMES[:4]:
                row[o] = round(100.0 * sum(r["outcome"] == o for r in mine) / len(mine), 1)
            row.update({"time_s": _mean(r["duration_s"] for r in ok),
                        "path_m": _mean(r["path_length_m"] for r in ok),
                        "min_separation_m": _mean(r["min_separation_m"] for r in mine),
                        "discomfort_s": _mean(r["discomfort_s"] for r in mine),
                        "discomfort_pct": _mean(100.0 * float(r["discomfort_s"])
                                                / float(r["duration_s"]) for r in mine
                                                if float(r["duration_s"]) > 0),
                        "intrusions": _mean(r["intrusions"] for r in mine),
                        "irregularity_rad_per_m": _mean(r["irregularity_rad_per_m"]
                                                        for r in mine)})
            out.append(row)
    return out


def summary_markdown(summary: list[dict], seeds: Sequence[int], by: str = "people") -> str:
    header = ["planner", by, "runs", "success [%]", "collision [%]", "stagnated [%]",
              "timeout [%]", "time [s]", "path [m]", "min separation [m]", "discomfort [s]",
              "discomfort [% of the run]", "intrusions", "irregularity [rad/m]"]
    rows = [[r["planner"], r[by], r["runs"], r["reached"], r["collision"], r["stagnated"],
             r["timeout"], r["time_s"], r["path_m"], r["min_separation_m"], r["discomfort_s"],
             r["discomfort_pct"], r["intrusions"], r["irregularity_rad_per_m"]]
            for r in summary]
    return (f"# Crowd (offline, seeds {', '.join(map(str, seeds))}; a run = one robot's; time "
            "and path of the successful runs, the rest over all runs)\n\n"
            + markdown_table(header, rows))


def run_crowd(out: str | Path, planners: Sequence[str] = DEFAULT_PLANNERS,
              people: Sequence[int] = DEFAULT_PEOPLE, seeds: Sequence[int] = (0, 1, 2),
              timeout_s: float = 300.0, sets: Sequence[str] = (),
              sweep: SweepOptions | None = None, progress: bool | None = None,
              worlds: Sequence[str] = ()) -> list[dict]:
    """Run the experiment into ``out`` (the hall scenes; or, given ``worlds``, those worlds
    as they are, files ``crowd-worlds*``); return the summary rows."""
    from nodes.planner.registry import make_planner
    from worlds import load_world, world_path

    if not planners or not seeds or not (people or worlds):
        raise ConfigError("need at least one planner, one number of people and one seed")
    for name in planners:
        make_planner(name, None, list(sets))          # a bad name or setting: before any run
    out = Path(out)
    jobs = []
    if worlds:
        loaded = [(load_world(w), world_path(w).read_text(encoding="utf-8")) for w in worlds]
        jobs = [CrowdJob(w, planner, len(w.people), seed, timeout_s, tuple(sets), text)
                for w, text in loaded for seed in seeds for planner in planners]
    else:
        (out / "worlds").mkdir(parents=True, exist_ok=True)
        for n in people:
            for seed in seeds:
                world, text = crowd_scene(n, seed)
                replace_text((out / "worlds" / f"{world.name}.toml"), text)
                jobs += [CrowdJob(world, planner, n, seed, timeout_s, tuple(sets), text)
                         for planner in planners]
    opts = SweepOptions(workers=(sweep or SweepOptions()).workers,
                        scheduler=(sweep or SweepOptions()).scheduler, progress=progress)
    rows = [r for rs in _journaled_runs(jobs, opts, out) for r in rs]
    stem, by = ("crowd-worlds", "world") if worlds else ("crowd", "people")
    out.mkdir(parents=True, exist_ok=True)
    write_csv(rows, out / f"{stem}.csv")
    summary = summarize(rows, by)
    write_csv(summary, out / f"{stem}-summary.csv")
    replace_text((out / f"{stem}.md"), summary_markdown(summary, seeds, by))
    if not worlds:
        plot_summary(summary, out / "crowd.png")
    return summary


def _journaled_runs(jobs: list[CrowdJob], opts: SweepOptions, out: Path) -> list[list[dict]]:
    """Each job's rows, in job order: those finished before from ``out/runs/`` (the journal,
    :mod:`papf.experiments.journal`), the others run now, each written there as it ends."""
    journal = Journal(out)
    kept = {i: rows for i, rows in ((i, _resumed(journal, j)) for i, j in enumerate(jobs))
            if rows is not None}
    if kept:
        print(f"crowd: {len(kept)} of {len(jobs)} runs finished before, taken from "
              f"{journal.dir} (delete it to make them again)", file=sys.stderr)
    todo = [j for i, j in enumerate(jobs) if i not in kept]
    done = iter(map_runs(run_crowd_job, todo, opts,
                         label=lambda j: f"{j.planner} {j.world.name} seed {j.seed}", title="crowd",
                         line=lambda j, rows: f"{j.planner}, {j.world.name}, seed {j.seed}: "
                                              + ", ".join(r["outcome"] for r in rows),
                         on_done=lambda j, rows: journal.put(j.key, {"rows": rows})))
    return [kept[i] if i in kept else next(done) for i in range(len(jobs))]


def _resumed(journal: Journal, job: CrowdJob) -> list[dict] | None:
    """The rows of a finished run of ``job``, or None (not finished, or not rows: run again)."""
    data = journal.get(job.key)
    rows = None if data is None else data.get("rows")
    if not (isinstance(rows, list) and rows and all(isinstance(r, dict) for r in rows)):
        return None
    return rows


def plot_summary(summary: list[dict], png: Path) -> Path:
    """Success rate, min separation and discomfort against the number of people."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    panels = (("reached", "success [%]"), ("min_separation_m", "mean min separation [m]"),
              ("discomfort_pct", "discomfort [% of the run]"), ("intrusions", "mean intrusions"))
    fig, axes = plt.subplots(1, len(panels), figsize=(13, 3.4), layout="constrained")
    for ax, (key, label) in zip(axes, panels, strict=True):
        for planner in dict.fromkeys(r["planner"] for r in summary):
            pts = [(r["people"], r[key]) for r in summary
                   if r["planner"] == planner and r[key] != ""]
            if pts:
                ax.plot(*zip(*pts, strict=True), marker="o", label=planner)
        ax.set_xlabel("people")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle("papf experiment crowd (offline, ORCA people in a 11 x 6 m hall)")
    png.parent.mkdir(parents=True, exist_ok=True)
    with output(png, force=True) as tmp:   # beside, then renamed (common/outfiles.py)
        fig.savefig(tmp, dpi=100, format="png")
    plt.close(fig)
    return png
