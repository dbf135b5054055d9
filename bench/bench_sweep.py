"""Sweep throughput: full-stack runs per hour at ``--workers 1`` and ``2`` (JSON lines).

    papf bench sweep [--runs 4] [--timeout 30] [--workers 1,2]

Each sweep is ``--runs`` runs of the whole process stack (APF and PAPF alternating, seeds
1..N) on the ``energy`` world, each cut at ``--timeout`` s of sim time, spread by
:func:`papf.experiments.sweep.map_runs` (workers 1: one after the other; N: a Dask
LocalCluster of N worker processes, its start-up included). Speed is reported, never
asserted.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from papf.experiments.sweep import SweepOptions, map_runs  # noqa: E402
from papf.experiments.trials import quiet_runner_logs, run_job, trial_job  # noqa: E402
from worlds import load_world, world_path  # noqa: E402


def bench(runs: int, timeout_s: float, workers: int) -> dict:
    world = load_world("energy")
    jobs = [trial_job(world, world_path("energy"), planner=("apf", "papf")[k % 2], seed=k + 1,
                      mode="stack", timeout_s=timeout_s, index=k) for k in range(runs)]
    t0 = time.monotonic()
    done = map_runs(run_job, jobs, SweepOptions(workers=workers, progress=False),
                    label=lambda j: j.label, title=f"bench sweep x{workers}")
    wall = time.monotonic() - t0
    return {"bench": "sweep", "workers": workers, "runs": runs, "sim_s_per_run": timeout_s,
            "wall_s": round(wall, 2), "runs_per_hour": round(runs * 3600 / wall, 1),
            "outcomes": sorted({t.outcome for t, _ in done}), "cpus": os.cpu_count()}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=4, help="runs per sweep (4)")
    ap.add_argument("--timeout", type=float, default=30.0, help="sim seconds per run (30)")
    ap.add_argument("--workers", default="1,2", help="comma-separated worker counts (1,2)")
    a = ap.parse_args()
    quiet_runner_logs()
    for w in (int(x) for x in a.workers.split(",")):
        print(json.dumps(bench(a.runs, a.timeout, w)), flush=True)


if __name__ == "__main__":
    main()
