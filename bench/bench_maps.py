"""PAPF on the packaged map worlds (or any ``--worlds``), offline and through the stack:
outcome, collisions and x real time per world.

For each world (``--worlds``, default every packaged ``map-*`` world; the crowd and fleet
worlds too, where ``path_m`` is the JSON's: ``papf run`` sums a fleet's robots, ``papf
plan`` gives the first robot's): ``papf plan --world W
--planner P --json`` (offline: the planner core, the simulated LiDAR on the grid, the
ROSbot's unicycle) and ``papf run --world W --planner P --json`` (every node a process,
lockstep, pybullet). A row per world and mode: the map's cells, the JSON's outcome,
collisions, sim time and path, and ``sim_over_wall`` (sim time over the run's
``wall_time_s``; offline over the command's wall time). ``--csv FILE --label L`` writes the
rows labelled ``L`` (other labels kept), with the 1-minute load average of each.

    papf bench maps [--worlds map-rooms,map-campus] [--planner papf] [--timeout 900]
                    [--csv docs/data/map-runs.csv --label L]
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

from common.cliparse import ArgumentParser

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench.csvrows import check_csv, replace_label  # noqa: E402
from nodes.planner.registry import one_with_role  # noqa: E402
from worlds import load_world  # noqa: E402

FIELDS = ("label", "world", "cells", "mode", "planner", "outcome", "collisions", "sim_s",
          "path_m", "wall_s", "sim_over_wall", "load_avg_1min")
MODES = {"offline": "plan", "stack": "run"}   # mode -> papf command


def packaged_maps() -> list[str]:
    return sorted(p.stem for p in (ROOT / "worlds").glob("map-*.toml"))


def cells(world: str) -> int:
    """The number of cells of the world's map."""
    return sum(int(ob.grid.data.size) for ob in load_world(world).obstacles if ob.kind == "map")


def one(world: str, mode: str, planner: str, timeout_s: float) -> dict:
    """One ``papf plan|run`` of ``world``; its row (without the label)."""
    argv = [sys.executable, "-m", "papf", MODES[mode], "--world", world, "--planner", planner,
            "--timeout", str(timeout_s), "--json"]
    load = os.getloadavg()[0]
    t0 = time.perf_counter()
    out = subprocess.run(argv, capture_output=True, text=True, cwd=ROOT, timeout=timeout_s + 600)
    wall = time.perf_counter() - t0
    lines = [ln for ln in out.stdout.splitlines() if ln.startswith("{")]
    if not lines:
        raise SystemExit(f"bench maps: {' '.join(argv[2:])}: no JSON (exit {out.returncode}): "
                         f"{out.stderr.strip().splitlines()[-1:]}")
    res = json.loads(lines[-1])
    wall = res.get("wall_time_s", wall)
    return {"world": world, "mode": mode, "planner": planner, "outcome": res["outcome"],
            "collisions": res["collisions"], "sim_s": res["sim_time_s"],
            "path_m": round(res["path_length_m"], 2), "wall_s": round(wall, 2),
            "sim_over_wall": round(res["sim_time_s"] / wall, 1), "load_avg_1min": round(load, 1)}


def main() -> None:
    ap = ArgumentParser(prog="papf bench maps", description=__doc__.splitlines()[0])
    ap.add_argument("--worlds", default=",".join(packaged_maps()), help="map worlds (every map-*)")
    ap.add_argument("--planner", default=one_with_role("papf-proposed"))
    ap.add_argument("--timeout", type=float, default=900.0, help="sim seconds at most (900)")
    ap.add_argument("--csv", type=Path, help="write the rows here (with --label)")
    ap.add_argument("--label", default="run")
    a = ap.parse_args()
    if a.csv:   # a foreign file: refused before the work, not after
        check_csv(a.csv, FIELDS)
    if not 0 < a.timeout <= 3600:
        ap.error(f"--timeout {a.timeout}: give 0 < seconds <= 3600")
    rows = []
    for world in a.worlds.split(","):
        n = cells(world)
        for mode in MODES:
            row = {**one(world, mode, a.planner, a.timeout), "cells": n}
            print(json.dumps(row), flush=True)
            rows.append(row)
    if a.csv:
        replace_label(a.csv, FIELDS, a.label, rows)


if __name__ == "__main__":
    main()
