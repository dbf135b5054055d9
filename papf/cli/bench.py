"""``papf bench NAME [ARGS...]``: run one of the benchmarks in ``bench/`` (they print JSON).

Benchmarks measure speed and memory; tests never do. Each ``bench/bench_<name>.py``
is a script with its own ``--help``.
"""

from __future__ import annotations

import argparse
import runpy
import sys
from pathlib import Path

import bench

BENCHES = {
    "planner": "planner cycle time p50/p99 per planner, incl. the PAPF worst case (M = 10)",
    "planner_ab": "one planner case, this code against another checkout's, in alternating turns",
    "run_ab": "papf run, this code against another checkout's, alternated (wall, CPU, start-up)",
    "sim": "sim-time / wall-time of papf run (full stack, CPU per process); --loop: driver + LiDAR",
    "sweep": "full-stack runs per hour of a sweep at --workers 1 and 2 (Dask)",
    "recorder": "recorder node's sustained throughput without loss (messages/s)",
    "recorder-flood": "recorder under a 512 KB byte flood: peak memory, real odometry kept",
    "latency": "command-to-wheel latency over the robot/laptop split (p50/p99)",
    "view": "Foxglove viewer: CPU share, added latency; lockstep run with/without --view",
    "face": "ROS 2 face: CPU per planner cycle, added latency; lockstep run with/without --ros-face",
    "tracker": "obstacle tracker cycle time (300-beam scans) and its error against truth, road worlds",
    "fleet": "papf run with 1-8 robots and 0-50 people: x real time, CPU per robot-cycle",
    "fleet-chain": "a recorded lockstep fleet run: when each cycle's scans and commands came",
    "rx": "a Zenoh subscriber's CPU per received sample: callback or drained channel, main "
          "thread idle or busy",
    "maps": "PAPF on the packaged map worlds, offline and through the stack (outcome, x real time)",
    "link-drive": "papf run --link over slow links: outcome, time, round trip, refused commands "
                  "(this code or --checkout DIR's)",
    "link": "papf link's own cost: added one-way latency (p50/p99) at delay 0, throughput (MB/s)",
    "world-scale": "driver + LiDAR against world size: N obstacles, W x W m maps (x real time, "
                   "start-up, CPU per cycle, memory)",
    "suite": ".ci/run's steps on a fresh clone of a commit: wall and CPU of each, CPU per test file",
}


def register(subparsers) -> None:
    p = subparsers.add_parser("bench", help="run a benchmark (prints JSON)",
                              description=__doc__.splitlines()[0] + "\n\n" + "\n".join(
                                  f"  {k:10} {v}" for k, v in BENCHES.items()),
                              formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("name", choices=sorted(BENCHES))
    p.add_argument("args", nargs=argparse.REMAINDER, help="options of that benchmark (--help)")
    p.set_defaults(func=cmd_bench)


def cmd_bench(args: argparse.Namespace) -> int:
    script = Path(bench.__file__).parent / f"bench_{args.name.replace('-', '_')}.py"
    argv, sys.argv = sys.argv, [str(script), *args.args]
    try:
        runpy.run_path(str(script), run_name="__main__")
    except SystemExit as exc:
        if isinstance(exc.code, str):    # a benchmark's own one-line error
            print(f"papf bench {args.name}: {exc.code}", file=sys.stderr)
            return 2
        return int(exc.code or 0)
    finally:
        sys.argv = argv   # the caller's again (main() called in-process, by a test)
    return 0
