"""Before/after planner cycle time, interleaved: ``papf bench planner_ab --before DIR [options]``.

Times one case of :mod:`bench.bench_planner` (default: the PAPF worst case, ``trap`` with
``persist_quarks=false``) with the code of this tree and with the code of another checkout
(``--before DIR``, e.g. ``git worktree add /tmp/old 32cedc4``), in two worker processes
that take turns: ``--rounds`` rounds of ``--chunk`` cycles each. Load from other jobs then
falls on both alike, which a before run followed by an after run does not give on a shared
machine. Prints one JSON object per side and writes them with ``--csv`` (CPU time of the
worker thread to the command and for the whole step, p50 / p99 over every cycle, and the
1-minute load average range). Speed is reported, never asserted.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from bench.csvrows import check_csv, write_rows
from common.cliparse import ArgumentParser

HERE = Path(__file__).resolve().parent
FIELDS = ("date", "code", "planner", "settings", "scene", "cycles", "cmd_cpu_p50_us",
          "cmd_cpu_p99_us", "cpu_p50_us", "cpu_p99_us", "load_min", "load_max")


def worker(scene: str, planner: str, sets: list[str], chunk: int) -> None:
    """Serve chunks of cycles on stdin lines (the code imported is the PYTHONPATH tree's)."""
    sys.path.insert(0, str(HERE))
    from bench_planner import SCENES

    from nodes.planner.registry import make_planner
    from schemas.messages import Goal, Odometry
    from worlds.toy import cast_scan

    world, (x0, x1), goal = SCENES[scene]
    pl = make_planner(planner, sets=sets)
    xs = np.linspace(x0, x1, chunk)
    scans = [cast_scan(world, x, 0.0, 0.0, stamp_ns=k) for k, x in enumerate(xs)]
    odoms = [Odometry(stamp_ns=k, x=x, y=0.0, yaw=0.0, v=0.0, w=0.0) for k, x in enumerate(xs)]
    pl.set_goal(Goal(stamp_ns=0, x=goal[0], y=goal[1]))
    pl.step(scans[0], odoms[0])                       # warm-up (JIT compile)
    print("ready", flush=True)
    for _line in sys.stdin:
        cmd, step = [], []
        for scan, odom in zip(scans, odoms, strict=True):
            pl.set_goal(Goal(stamp_ns=0, x=goal[0], y=goal[1]))
            pl.state = "driving"
            c0 = time.thread_time_ns()
            _, finish = pl.command(scan, odom)
            c1 = time.thread_time_ns()
            finish()
            cmd.append(c1 - c0)
            step.append(time.thread_time_ns() - c0)
        print(json.dumps([cmd, step]), flush=True)


def compare(trees: dict[str, Path], args) -> list[dict]:
    cmd = [sys.executable, str(Path(__file__).resolve()), "--serve", "--scene", args.scene,
           "--planner", args.planner, "--chunk", str(args.chunk), *sum((["--set", s] for s in args.set), [])]
    procs = {label: subprocess.Popen(cmd, cwd=tree, env={**os.environ, "PYTHONPATH": str(tree)},
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
             for label, tree in trees.items()}
    for label, p in procs.items():
        if p.stdout.readline().strip() != "ready":
            raise SystemExit(f"the {label} worker did not start (see its error above)")
    times = {label: ([], []) for label in trees}
    loads = []
    for _ in range(args.rounds):
        loads.append(os.getloadavg()[0])
        for label, p in procs.items():
            p.stdin.write("go\n")
            p.stdin.flush()
            c, s = json.loads(p.stdout.readline())
            times[label][0].extend(c)
            times[label][1].extend(s)
    for p in procs.values():
        p.stdin.close()
        p.wait()
    date = time.strftime("%Y-%m-%dT%H:%M", time.gmtime())
    rows = []
    for label, (c, s) in times.items():
        c_us, s_us = np.array(c) / 1e3, np.array(s) / 1e3
        rows.append({"date": date, "code": label, "planner": args.planner, "settings": " ".join(args.set),
                     "scene": args.scene, "cycles": len(c),
                     "cmd_cpu_p50_us": round(float(np.percentile(c_us, 50)), 1),
                     "cmd_cpu_p99_us": round(float(np.percentile(c_us, 99)), 1),
                     "cpu_p50_us": round(float(np.percentile(s_us, 50)), 1),
                     "cpu_p99_us": round(float(np.percentile(s_us, 99)), 1),
                     "load_min": round(min(loads), 1), "load_max": round(max(loads), 1)})
    return rows


def main() -> None:
    from nodes.planner.registry import one_with_role  # this checkout's registry, not --before's

    proposed = one_with_role("papf-proposed")
    ap = ArgumentParser(prog="papf bench planner_ab", description=__doc__.splitlines()[0])
    ap.add_argument("--before", type=Path, help="root of the other checkout (the 'before' code)")
    ap.add_argument("--labels", default="before,after", help="names of the two sides (before,after)")
    ap.add_argument("--planner", default=proposed)
    ap.add_argument("--set", action="append", default=None,
                    help="planner setting, repeatable (default for PAPF: persist_quarks=false, "
                         "the worst case; none for the others)")
    ap.add_argument("--scene", default="trap")
    ap.add_argument("--rounds", type=int, default=30, help="turns per side (30)")
    ap.add_argument("--chunk", type=int, default=50, help="cycles per turn (50)")
    ap.add_argument("--csv", type=Path, help="write the two rows to this CSV")
    ap.add_argument("--serve", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.csv:   # a foreign file: refused before the work, not after
        check_csv(args.csv, FIELDS)
    if args.set is None:
        args.set = ["persist_quarks=false"] if args.planner == proposed else []
    if args.serve:
        worker(args.scene, args.planner, args.set, args.chunk)
        return
    if args.before is None or not (args.before / "nodes" / "planner").is_dir():
        ap.error(f"--before {args.before}: expected the root of a papf-stack checkout")
    if args.rounds < 1 or args.chunk < 2:
        ap.error("--rounds must be >= 1 and --chunk >= 2")
    names = args.labels.split(",")
    if len(names) != 2:
        ap.error(f"--labels {args.labels!r}: expected two names, e.g. before,after")
    rows = compare({names[0]: args.before.resolve(), names[1]: HERE.parent}, args)
    for row in rows:
        print(json.dumps(row))
    if args.csv:
        write_rows(args.csv, FIELDS, rows)


if __name__ == "__main__":
    main()
