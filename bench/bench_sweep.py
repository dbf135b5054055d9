"""Sweep throughput: full-stack runs per hour at ``--workers 1`` and ``2`` (JSON lines, CSV).

    papf bench sweep [--runs 8] [--timeout 300] [--workers 1,2] [--csv FILE]

Each sweep is ``--runs`` runs of the whole process stack on the ``energy`` world, APF and
PAPF alternating (seeds 1..N), each to its end (goal reached; ``--timeout`` caps the sim
time), spread by :func:`papf.experiments.sweep.map_runs` (workers 1: one after the other
in this process; N: a Dask LocalCluster of N single-threaded worker processes, its
start-up and shut-down included). Per sweep: wall time, runs per hour, sim seconds per
wall second, CPU seconds of every process the sweep started (from /proc: steadier than
wall time when other jobs share the cores) and the 1-minute load average before and
after. ``--csv`` writes one row per sweep (``docs/data/bench-sweep.csv``; ``make docs``
renders the tables in docs/performance.md and docs/sweeps.md). Speed is reported, never
asserted.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from pathlib import Path

from common.cliparse import ArgumentParser

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.csvrows import check_csv, write_rows  # noqa: E402
from bench.proc_cpu import TreeCPU  # noqa: E402
from nodes.planner.registry import one_with_role  # noqa: E402
from papf.experiments.sweep import SweepOptions, map_runs  # noqa: E402
from papf.experiments.trials import quiet_runner_logs, run_job, trial_job  # noqa: E402
from worlds import load_world, world_path  # noqa: E402

FIELDS = ("date", "machine", "cpus", "workers", "runs", "planners", "outcomes", "sim_s",
          "wall_s", "runs_per_hour", "sim_per_wall", "cpu_s", "cpu_s_per_run", "load_before",
          "load_after")


def bench(runs: int, timeout_s: float, workers: int) -> dict:
    """``runs`` energy runs through the stack, the PAPF paper's two planners alternating."""
    world = load_world("energy")
    pair = one_with_role("papf-baseline"), one_with_role("papf-proposed")
    jobs = [trial_job(world, world_path("energy"), planner=pair[k % 2], seed=k + 1,
                      mode="stack", timeout_s=timeout_s, index=k) for k in range(runs)]
    load0 = os.getloadavg()[0]
    t0 = time.monotonic()
    with TreeCPU(period_s=0.2) as cpu:
        done = map_runs(run_job, jobs, SweepOptions(workers=workers, progress=False),
                        label=lambda j: j.label, title=f"bench sweep x{workers}")
    wall = time.monotonic() - t0
    cpu_s = sum(p["cpu_s"] for p in cpu.per_process().values())
    trials = [t for t, _ in done]
    sim_s = sum(t.duration_s for t in trials)
    return {"date": time.strftime("%Y-%m-%dT%H:%M", time.gmtime()),
            "machine": platform.processor() or platform.machine(), "cpus": os.cpu_count(),
            "workers": workers, "runs": runs, "planners": "apf,papf",
            "outcomes": " ".join(sorted({t.outcome for t in trials})),
            "sim_s": round(sim_s, 1), "wall_s": round(wall, 1),
            "runs_per_hour": round(runs * 3600 / wall), "sim_per_wall": round(sim_s / wall, 1),
            "cpu_s": round(cpu_s, 1), "cpu_s_per_run": round(cpu_s / runs, 1),
            "load_before": round(load0, 1), "load_after": round(os.getloadavg()[0], 1),
            "durations_s": [round(t.duration_s, 2) for t in trials]}   # JSON only, per run


def _workers(text: str) -> list[int]:
    try:
        out = [int(x) for x in text.split(",")]
    except ValueError:
        out = []
    if not out or min(out) < 1:
        raise argparse.ArgumentTypeError(f"{text!r}: expected worker counts >= 1, e.g. 1,2")
    return out


def main() -> None:
    ap = ArgumentParser(prog="papf bench sweep", description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=8, help="runs per sweep (8)")
    ap.add_argument("--timeout", type=float, default=300.0,
                    help="sim seconds at most per run (300: every run ends at the goal)")
    ap.add_argument("--workers", type=_workers, default=[1, 2],
                    help="comma-separated worker counts (1,2)")
    ap.add_argument("--csv", type=Path, help="write one row per sweep to this CSV")
    ap.add_argument("--append", action="store_true", help="add the rows to --csv instead of replacing it")
    a = ap.parse_args()
    if a.csv:   # a foreign file: refused before the work, not after
        check_csv(a.csv, FIELDS)
    if a.runs < 1 or a.timeout <= 0:
        ap.error("--runs must be >= 1 and --timeout > 0")
    quiet_runner_logs()
    rows = []
    for w in a.workers:
        rows.append(bench(a.runs, a.timeout, w))
        print(json.dumps(rows[-1]), flush=True)
    if a.csv:
        write_rows(a.csv, FIELDS, rows, a.append)


if __name__ == "__main__":
    main()
