"""``papf experiment crowd``: planners x scenes x seeds among people, with the field's measures.

The scene of ``(people, seed)`` (:func:`crowd_scene`): a walled hall ``HALL_X`` x ``HALL_Y``;
the robot drives from (0, 0) to (8, 0) along its middle. ``people`` pedestrians (ORCA, radius
0.3 m) are drawn from ``numpy.random.default_rng([seed, people])``: each, in turn, is a
*walker along* the hall (start near one end, goal near the other: head-on or overtaking
traffic) or a *walker across* it (start near one long wall, goal near the other, at a random
x), with a preferred speed uniform in ``SPEED_M_S``; starts and goals keep
``CLEAR_M`` from each other and from the robot's start and goal. Each walks to its goal and
back, in a loop, so the hall stays as busy for the whole run. Every scene is written as a
world file (``OUT/worlds/``): ``papf plan --world OUT/worlds/crowd-N-S.toml`` repeats a run.

The other scenes (:mod:`papf.experiments.crowd_scenes`): ``groups`` (standing groups, people
standing alone, a pair walking together, walkers) and ``replay`` (a track file replayed blind
to the robot; by default the packaged recording, ``--replay F1,F2`` given ones, e.g. ETH/UCY
files). ``--scenes hall,groups,replay`` picks them (the hall once per ``--people`` number).

Each run is :func:`papf.offline.run.simulate` (offline, :mod:`papf.offline.crowd`), spread by
:func:`papf.experiments.sweep.map_runs` (``--workers`` / ``--scheduler``). Writes
``OUT/crowd.csv`` (a row per run: outcome, time, path, collisions by kind and by who caused
them, and every measure of :mod:`common.crowd_measures` and the people's path and time
extension), ``OUT/crowd-summary.csv`` and ``OUT/crowd.md`` (per planner x scene: rates with
their 95 % Wilson intervals, means with 95 % t-interval half-widths,
:mod:`papf.experiments.crowd_stats`), ``OUT/crowd.png`` (those figures with their intervals)
and ``OUT/crowd-scenes.png`` (each scene of the first seed: the world, the people - walking,
standing, groups - and every planner's path).
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from common.errors import ConfigError
from common.outfiles import replace_text
from nodes.planner.registry import with_role
from papf.experiments.crowd_scenes import (  # noqa: F401 (re-exported: the hall's scene)
    GOAL,
    HALL_X,
    HALL_Y,
    MAX_HALL_PEOPLE,
    START,
    crowd_scene,
)
from papf.experiments.journal import Journal, run_key
from papf.experiments.sweep import SweepOptions, map_runs
from papf.experiments.trials import markdown_table, write_csv
from worlds import World

DEFAULT_PLANNERS = with_role("crowd")     # the planners compared among people
DEFAULT_PEOPLE = (10,)
SCENES = ("hall", "groups", "replay")
OUTCOMES = ("reached", "collision", "stagnated", "timeout", "failed")


@dataclass(frozen=True)
class CrowdJob:
    """One run: ``planner`` on ``world`` (a scene, or a packaged world)."""

    world: World
    planner: str
    people: int
    seed: int
    timeout_s: float = 300.0
    sets: tuple[str, ...] = ()
    world_text: str = ""       # the world's TOML: what defines the run (its journal key)
    scene: str = ""            # the scene's label (hall-10, groups, replay-<file>)
    trace: bool = False        # keep the paths and the people's tracks (the scene picture)

    @property
    def key(self) -> str:
        """The run's journal key (:func:`papf.experiments.journal.run_key`)."""
        return run_key("crowd", self.world.name, self.world_text, self.planner, self.people,
                       self.seed, self.timeout_s, self.sets, self.trace)


#: the per-run figures of a robot's ``papf plan --json`` object kept in the CSV, as named there
MEASURES = ("collisions_wall", "collisions_robot", "collisions_person",
            "collisions_person_by_robot", "collisions_person_by_person", "min_separation_m",
            "discomfort_s", "intrusions", "path_irregularity_rad_per_m", "intimate_s",
            "intimate_n", "personal_s", "personal_n", "social_s", "social_n",
            "group_intrusions", "group_s", "min_ttc_s", "people_compared", "people_held",
            "people_path_ext_m", "people_time_ext_s")
TRACE_STEP_S = 0.5             # [s] the scene picture's sampling of paths and people


def run_crowd_job(job: CrowdJob) -> dict:
    """One offline run -> ``{"rows": a CSV row per robot, "trace": ...}`` (the trace only
    when ``job.trace``; nothing of wall time: rows depend on the run alone)."""
    from papf.offline.crowd import plan_crowd  # also with 0 people: the crowd measures

    res = plan_crowd(job.world, job.planner, list(job.sets), None, job.seed, job.timeout_s, 0.1)
    rows = [{"world": job.world.name, "scene": job.scene or job.world.name, "robot": r["name"],
             "planner": r["planner"], "people": job.people, "seed": job.seed,
             "outcome": r["outcome"], "duration_s": round(r["duration_s"], 3),
             "path_length_m": round(r["path_length_m"], 3),
             **{k: _cell(r.get(k)) for k in MEASURES}}
            for r in res.crowd["robots"]]
    return {"rows": rows, "trace": _trace(res.trace) if job.trace else None}


def _cell(v):
    """A CSV cell: rounded, '' for None (nobody to measure against)."""
    return "" if v is None else round(v, 3) if isinstance(v, float) else v


def _trace(run) -> dict:
    """The run's paths and people, every TRACE_STEP_S, as JSON lists (the scene picture)."""
    every = max(1, round(TRACE_STEP_S / 0.1))
    shown = run.shown if run.shown is not None else np.broadcast_to(run.radii, run.people.shape[:2])
    return {"paths": {r.name: np.round(r.result.path[::every], 3).tolist() for r in run.robots},
            "people": np.round(run.people[::every], 3).tolist(),
            "shown": np.round(shown[::every], 3).tolist()}


def summarize(rows: list[dict], by: str = "scene") -> list[dict]:
    """Per planner x ``by`` (scene, people or world): rates [%] over the robots' runs with
    their 95 % Wilson intervals, and every figure's mean with its 95 % t-interval half-width
    (:mod:`papf.experiments.crowd_stats`); time and path of the successful runs only."""
    from papf.experiments.crowd_stats import t_interval, wilson

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
            row["reached_lo"], row["reached_hi"] = wilson(len(ok), len(mine))
            hit = sum(r["outcome"] == "collision" for r in mine)
            row["collision_lo"], row["collision_hi"] = wilson(hit, len(mine))
            figures = {"time_s": [r["duration_s"] for r in ok],
                       "path_m": [r["path_length_m"] for r in ok],
                       "discomfort_pct": [100.0 * float(r["discomfort_s"]) / float(r["duration_s"])
                                          for r in mine if float(r["duration_s"]) > 0],
                       "irregularity_rad_per_m": [r.get("irregularity_rad_per_m",
                                                        r.get("path_irregularity_rad_per_m", ""))
                                                  for r in mine]}
            for k in MEASURES:
                if k in mine[0]:
                    figures[k] = [r[k] for r in mine]
            for k, values in figures.items():
                row[k], row[f"{k}_ci"] = t_interval(values)
            out.append(row)
    return out


#: the two tables of crowd.md (and docs/experiments.md): (CSV column, header)
TABLE_OUTCOMES = (("reached", "success [%]"), ("collision", "collision [%]"),
                  ("time_s", "time [s]"), ("path_m", "path [m]"),
                  ("collisions_person_by_robot", "hit by robot"),
                  ("collisions_person_by_person", "hit by person"),
                  ("min_separation_m", "min separation [m]"))
TABLE_SOCIAL = (("intimate_s", "intimate [s]"), ("personal_s", "personal [s]"),
                ("personal_n", "personal entries"), ("group_intrusions", "group intrusions"),
                ("min_ttc_s", "min TTC [s]"), ("people_time_ext_s", "people +time [s]"),
                ("people_path_ext_m", "people +path [m]"))


def _with_ci(row: dict, key: str) -> str:
    """``mean ± half-width`` (a rate: ``rate [lo, hi]``)."""
    if key in ("reached", "collision"):
        return f"{row[key]} [{row[key + '_lo']}, {row[key + '_hi']}]"
    v, ci = row.get(key, ""), row.get(f"{key}_ci", "")
    return "" if v == "" else f"{v} ± {ci}" if ci != "" else f"{v}"


def summary_markdown(summary: list[dict], seeds: Sequence[int], by: str = "scene") -> str:
    if by != "scene":     # the packaged worlds and the people sweep: one table of means
        header = ["planner", by, "runs", "success [%]", "collision [%]", "stagnated [%]",
                  "timeout [%]", "time [s]", "path [m]", "min separation [m]", "discomfort [s]",
                  "discomfort [% of the run]", "intrusions", "irregularity [rad/m]"]
        keys = ("runs", "reached", "collision", "stagnated", "timeout", "time_s", "path_m",
                "min_separation_m", "discomfort_s", "discomfort_pct", "intrusions",
                "irregularity_rad_per_m")
        body = [[r["planner"], r[by], *(r.get(k, "") for k in keys)] for r in summary]
        return (f"# Crowd (offline, seeds {', '.join(map(str, seeds))}; a run = one robot's; "
                "time and path of the successful runs, the rest over all runs)\n\n"
                + markdown_table(header, body))
    parts = [f"# Crowd (offline, {len(seeds)} seeds: {seeds[0]}-{seeds[-1]}; mean ± 95 % "
             "t-interval half-width over the runs, rates with their 95 % Wilson interval; "
             "time and path of the successful runs)"]
    for title, table in (("Outcomes", TABLE_OUTCOMES), ("Social measures", TABLE_SOCIAL)):
        header = ["planner", "scene", "runs", *(h for _, h in table)]
        body = [[r["planner"], r["scene"], r["runs"], *(_with_ci(r, k) for k, _ in table)]
                for r in summary]
        parts += [f"## {title}", markdown_table(header, body)]
    return "\n\n".join(parts) + "\n"


def scene_jobs(planners: Sequence[str], people: Sequence[int], seeds: Sequence[int],
               scenes: Sequence[str], replay: Sequence[str], timeout_s: float,
               sets: Sequence[str], out: Path) -> list[CrowdJob]:
    """Every run of the scenes (module doc), each scene's world written to ``out/worlds/``."""
    from papf.experiments.crowd_scenes import groups_scene, packaged_tracks, replay_scene

    made = []
    for seed in seeds:
        if "hall" in scenes:
            made += [(f"hall-{n}", n, crowd_scene(n, seed), seed) for n in people]
        if "groups" in scenes:
            made.append(("groups", None, groups_scene(seed), seed))
        if "replay" in scenes:
            for f in replay or [str(packaged_tracks())]:
                made.append((f"replay-{Path(f).stem}", None, replay_scene(f, seed), seed))
    (out / "worlds").mkdir(parents=True, exist_ok=True)
    jobs = []
    for label, n, (world, text), seed in made:
        replace_text(out / "worlds" / f"{world.name}.toml", text)
        jobs += [CrowdJob(world, planner, n if n is not None else world.n_people, seed,
                          timeout_s, tuple(sets), text, label, seed == seeds[0])
                 for planner in planners]
    return jobs


def run_crowd(out: str | Path, planners: Sequence[str] = DEFAULT_PLANNERS,
              people: Sequence[int] = DEFAULT_PEOPLE, seeds: Sequence[int] = (0, 1, 2),
              timeout_s: float = 300.0, sets: Sequence[str] = (),
              sweep: SweepOptions | None = None, progress: bool | None = None,
              worlds: Sequence[str] = (), scenes: Sequence[str] = ("hall",),
              replay: Sequence[str] = ()) -> list[dict]:
    """Run the experiment into ``out`` (the scenes; or, given ``worlds``, those worlds as
    they are, files ``crowd-worlds*``); return the summary rows."""
    from nodes.planner.registry import make_planner
    from worlds import load_world, world_path

    if not planners or not seeds or not (people or worlds or set(scenes) - {"hall"}):
        raise ConfigError("need at least one planner, one scene (or number of people) and "
                          "one seed")
    for name in planners:
        make_planner(name, None, list(sets))          # a bad name or setting: before any run
    out = Path(out)
    if worlds:
        loaded = [(load_world(w), world_path(w).read_text(encoding="utf-8")) for w in worlds]
        jobs = [CrowdJob(w, planner, w.n_people, seed, timeout_s, tuple(sets), text)
                for w, text in loaded for seed in seeds for planner in planners]
    else:
        jobs = scene_jobs(planners, people, seeds, scenes, replay, timeout_s, sets, out)
    opts = SweepOptions(workers=(sweep or SweepOptions()).workers,
                        scheduler=(sweep or SweepOptions()).scheduler, progress=progress)
    results = _journaled_runs(jobs, opts, out)
    rows = [r for res in results for r in res["rows"]]
    stem, by = ("crowd-worlds", "world") if worlds else ("crowd", "scene")
    out.mkdir(parents=True, exist_ok=True)
    write_csv(rows, out / f"{stem}.csv")
    summary = summarize(rows, by)
    write_csv(summary, out / f"{stem}-summary.csv")
    replace_text((out / f"{stem}.md"), summary_markdown(summary, seeds, by))
    if not worlds:
        from papf.plots.crowd import plot_crowd_scenes, plot_crowd_summary

        plot_crowd_summary(summary, out / "crowd.png")
        plot_crowd_scenes(_scene_traces(jobs, results), out / "crowd-scenes.png")
    return summary


def _scene_traces(jobs: list[CrowdJob], results: list[dict]) -> list[dict]:
    """Per scene of the first seed: its world and every planner's path, the people's tracks
    (of the scene's longest run: they are the same people in every run until it ends)."""
    scenes: dict[str, dict] = {}
    for job, res in zip(jobs, results, strict=True):
        trace = res.get("trace")
        if not trace:
            continue
        s = scenes.setdefault(job.scene, {"world": job.world, "label": job.scene, "paths": {},
                                          "people": [], "shown": []})
        if len(trace["people"]) > len(s["people"]):
            s["people"], s["shown"] = trace["people"], trace["shown"]
        for name, path in trace["paths"].items():
            s["paths"][job.planner if name == "robot" else f"{job.planner} {name}"] = path
    return list(scenes.values())


def _journaled_runs(jobs: list[CrowdJob], opts: SweepOptions, out: Path) -> list[dict]:
    """Each job's result, in job order: those finished before from ``out/runs/`` (the journal,
    :mod:`papf.experiments.journal`), the others run now, each written there as it ends."""
    journal = Journal(out)
    kept = {i: res for i, res in ((i, _resumed(journal, j)) for i, j in enumerate(jobs))
            if res is not None}
    if kept:
        print(f"crowd: {len(kept)} of {len(jobs)} runs finished before, taken from "
              f"{journal.dir} (delete it to make them again)", file=sys.stderr)
    todo = [j for i, j in enumerate(jobs) if i not in kept]
    done = iter(map_runs(run_crowd_job, todo, opts,
                         label=lambda j: f"{j.planner} {j.world.name} seed {j.seed}", title="crowd",
                         line=lambda j, res: f"{j.planner}, {j.world.name}, seed {j.seed}: "
                                             + ", ".join(r["outcome"] for r in res["rows"]),
                         on_done=lambda j, res: journal.put(j.key, res)))
    return [kept[i] if i in kept else next(done) for i in range(len(jobs))]


def _resumed(journal: Journal, job: CrowdJob) -> dict | None:
    """The result of a finished run of ``job``, or None (not finished, or not rows: run again)."""
    data = journal.get(job.key)
    rows = None if data is None else data.get("rows")
    if not (isinstance(rows, list) and rows and all(isinstance(r, dict) for r in rows)):
        return None
    if job.trace and not isinstance(data.get("trace"), dict):
        return None
    return data
