"""``papf experiment traffic``: every planner on the ROSbot-scale road worlds, full stack.

IAPF (truth and tracker tracks), APF, PAPF, AR-APF on each ``road-*`` world through the
whole stack, recorded; road figures from the recordings' ground truth. Writes
``OUT/traffic.csv`` and ``OUT/traffic.md``. Details: :func:`run_traffic`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from common import robot
from common.errors import RecordingError
from common.outfiles import replace_text
from nodes.planner.registry import declared, with_role
from nodes.planner.road import Lanes
from papf.experiments.journal import Journal, run_key
from papf.experiments.trials import markdown_table, quiet_runner_logs, run_stack, write_csv
from papf.offline.car import road_figures
from worlds import load_world, packaged_worlds, world_path

ROAD_WORLDS = tuple(w for w in packaged_worlds() if w.startswith("road-"))
# (planner, objects): the planners that read tracks with the sim's and the tracker's, then
# those that declare the role "traffic" without tracks
CASES = (tuple((p, o) for p in declared("uses_objects") for o in ("truth", "tracker"))
         + tuple((p, "none") for p in with_role("traffic")))
STARTUP_S = 180.0   # [s wall] for the nodes to come up: JIT warm-ups are slow on a busy machine
HEADER = ["world", "planner", "objects", "outcome", "duration [s]", "path [m]", "collisions",
          "left road", "lane changes", "min speed [m/s]", "max speed [m/s]"]


def recorded_poses(mcap: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(times [s], (N, 2) positions [m], headings [rad]) of ``sim/pose`` in a recording."""
    from papf.recording.reader import iter_messages  # mcap: only with a recording

    rows = []
    try:
        for _key, msg, _t in iter_messages(mcap, keys="*/sim/pose"):
            rows.append((msg.stamp_ns * 1e-9, msg.x, msg.y, msg.yaw))
    except RecordingError:
        pass
    a = np.array(rows, dtype=float).reshape(-1, 4)
    return a[:, 0], a[:, 1:3], a[:, 3]


def road_row(world_name: str, planner: str, objects: str, trial, mcap: Path) -> dict:
    """The CSV row of one run: the run's figures and the road figures of its path."""
    world = load_world(world_name)
    road = world.road
    times, path, yaw = recorded_poses(mcap)
    moving = np.flatnonzero(np.linalg.norm(path - path[:1], axis=1) > 0.01) if len(path) else []
    first = int(moving[0]) if len(moving) else len(path)
    figures = {"left_road": "", "lane_changes": "", "min_speed_mps": "", "max_speed_mps": ""}
    if road is not None and first < len(path) - 1:
        figures = road_figures(Lanes(road.y_min, road.lane_width, road.lanes), times[first:],
                               path[first:], yaw[first:],
                               (robot.BODY_LENGTH_M, robot.BODY_WIDTH_M))
    return {"world": world_name, "planner": planner, "objects": objects,
            "seed": trial.seed, "outcome": trial.outcome,
            "duration_s": round(trial.duration_s, 2), "path_length_m": round(trial.path_length_m, 3),
            "collisions": trial.collisions, **figures, "wall_time_s": round(trial.wall_time_s, 1),
            "reason": trial.reason}


def table(rows: Sequence[dict]) -> str:
    """The traffic experiment's table (Markdown), one row per run."""
    def num(x, nd=2):
        return f"{x:.{nd}f}" if isinstance(x, float) and math.isfinite(x) else str(x)

    return markdown_table(HEADER, [[r["world"], r["planner"], r["objects"], r["outcome"],
                                    num(r["duration_s"], 1), num(r["path_length_m"]),
                                    r["collisions"], r["left_road"], r["lane_changes"],
                                    num(r["min_speed_mps"]), num(r["max_speed_mps"])]
                                   for r in rows])


def run_traffic(out: str | Path, worlds: Sequence[str] = ROAD_WORLDS,
                cases: Sequence[tuple[str, str]] = CASES, seed: int = 0,
                timeout_s: float = 150.0, echo=print,
                seeds: Sequence[int] | None = None) -> list[dict]:
    """Run every (seed, world, case) through the stack (``seeds``: default ``(seed,)``);
    write ``traffic.csv`` and ``traffic.md``.

    For each ``road-*`` world and each case — IAPF with the sim's ground-truth tracks
    (``--objects truth``), IAPF with the tracker node's tracks (``--objects tracker``), and
    APF, PAPF, AR-APF (no road model, no tracks) — one run of the whole process stack,
    recorded to ``OUT/recordings/<world>-<planner>-<objects>.mcap``. From the recording's
    ground-truth poses (``sim/pose``): ``left_road`` (a corner of the ROSbot's footprint
    ever beyond a solid line), ``lane_changes`` (the centre crossed a broken line),
    ``min_speed_mps`` / ``max_speed_mps`` after the first motion
    (:func:`papf.offline.car.road_figures`). Writes ``OUT/traffic.csv`` (one row per run) and
    ``OUT/traffic.md`` (the table). Each finished run's row is kept in ``OUT/runs/`` the moment
    it ends (:mod:`papf.experiments.journal`): after Ctrl-C the same command makes only the
    runs not made yet.
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    quiet_runner_logs()
    rows = []
    seeds = tuple(seeds) if seeds else (seed,)
    journal = Journal(out)   # each finished run on disk as it ends; a re-run resumes
    for s in seeds:
        for name in worlds:
            text = world_path(name).read_text(encoding="utf-8")
            for planner, objects in cases:
                key = run_key("traffic", name, text, planner, objects, s, timeout_s)
                row = journal.get(key)
                if row is None:
                    tag = f"-s{s}" if len(seeds) > 1 else ""
                    mcap = out / "recordings" / f"{name}-{planner}-{objects}{tag}.mcap"
                    trial = run_stack(world_path(name), planner, s, timeout_s, record=mcap,
                                      objects=objects, startup_timeout_s=STARTUP_S)
                    row = road_row(name, planner, objects, trial, mcap)
                    journal.put(key, row)
                rows.append(row)
                r = rows[-1]
                echo(f"{name:>17} {planner:<6} {objects:<8} seed {s} {r['outcome']:<9} "
                     f"{r['duration_s']:7.2f} s  collisions {r['collisions']}  "
                     f"left road {r['left_road']}  {r['reason']}")
    if journal.taken:
        echo(f"traffic: {journal.taken} of {len(rows)} runs finished before, taken from "
             f"{journal.dir} (delete it to make them again)")
    write_csv(rows, out / "traffic.csv")
    replace_text((out / "traffic.md"), table(rows))
    return rows
