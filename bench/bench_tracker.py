"""Tracker cycle time and accuracy on the road worlds: ``python bench/bench_tracker.py``.

For each ``road-*`` world (or ``--world W``, repeatable) a scripted robot drives along the
road's right edge, 0.25 m outside the solid line (y = y_min - 0.25), at 0.2 m/s for
``--seconds`` of sim time, so it passes every car without touching one and sees them from
behind, beside and in front, occluding each other. At each 10 Hz scan instant the
simulated LiDAR (300 beams, 1 cm noise, the stack's defaults) casts a scan, the
tracker (:class:`nodes.tracker.core.Tracker`, default settings) updates, and its
confirmed tracks are compared with the world's ground truth at that instant:

- a track matches the nearest true obstacle centre within ``--match`` m (1.0);
- ``pos_err_m``: distance between the track's and the true centre. The LiDAR sees one or
  two faces of a car, so the track lies on the visible part: up to half a car length
  (0.25 m) of this is the hidden far side, not filter error;
- ``vel_err_mps``: norm of the velocity difference;
- ``coverage``: share of (instant, true obstacle within 4 m of the robot) with a matching
  track; ``false_tracks``: share of confirmed tracks with no true obstacle near.

Timing is the wall time of ``Tracker.update`` (clustering + association + filter + the
message): p50, p99, max, and the thread's CPU time p50/p99 (less disturbed when other
processes share the cores); ``--no-numba`` times the numpy clustering instead of the
compiled one. Prints one JSON object per world, each with the machine's 1-minute load
average at its end (``load_avg``: other processes on the cores inflate the wall-time
p99); ``--csv FILE`` also writes the rows as CSV (appending to an existing file, so the
numba and numpy runs can share one). Speed is reported, never asserted (tests/ do not
time anything).
"""

from __future__ import annotations

import json
import math
import os
import platform
import time
from pathlib import Path

import numpy as np

from bench.csvrows import write_rows
from common.cliparse import ArgumentParser
from common.ports import plain
from nodes.lidar_sim.core import LidarParams, LidarSim
from nodes.tracker.core import Tracker, TrackerParams
from nodes.tracker.kernels import HAVE_NUMBA
from schemas.messages import Odometry
from worlds import load_world, packaged_worlds
from worlds.messages import truth_objects

SCAN_NS = 100_000_000    # [ns] 10 Hz, the stack's scan rate
SPEED = 0.2              # [m/s] of the scripted robot
EDGE_OFFSET = 0.25       # [m] the scripted robot's path, outside the right road edge
NEAR = 4.0               # [m] true obstacles this close count for coverage


def run_world(name: str, seconds: float, match: float, seed: int, numba: bool = True) -> dict:
    world = load_world(name)
    y = (world.road.y_min if world.road else 0.0) - EDGE_OFFSET
    tracker = Tracker(TrackerParams(use_numba=numba))
    tracker.warm_up()                                     # numba compile: not a cycle
    times, cpu, pos, vel = [], [], [], []
    near_total = near_hit = tracks_total = tracks_false = 0
    with LidarSim(world, LidarParams(), seed) as lidar:
        for k in range(int(seconds * 1e9 / SCAN_NS) + 1):
            t = k * SCAN_NS
            x = world.start[0] + SPEED * t * 1e-9
            odom = Odometry(stamp_ns=t, x=x, y=y, yaw=0.0, v=SPEED, w=0.0)
            scan = lidar.scan(x, y, 0.0, t)
            t0, c0 = time.perf_counter_ns(), time.thread_time_ns()
            out = tracker.update(scan, odom)
            times.append(time.perf_counter_ns() - t0)
            cpu.append(time.thread_time_ns() - c0)
            truth = truth_objects(world, t).tracks
            centres = np.array([(o.x, o.y) for o in truth]).reshape(-1, 2)
            matched = set()
            for tr in out.tracks:
                tracks_total += 1
                d = np.hypot(*(centres - (tr.x, tr.y)).T) if len(truth) else np.array([])
                if not len(d) or d.min() > match:
                    tracks_false += 1
                    continue
                i = int(d.argmin())
                matched.add(i)
                pos.append(float(d[i]))
                vel.append(math.hypot(tr.vx - truth[i].vx, tr.vy - truth[i].vy))
            for i, o in enumerate(truth):
                if math.hypot(o.x - x, o.y - y) <= NEAR:
                    near_total += 1
                    near_hit += i in matched
    us, cpu_us = np.array(times) / 1e3, np.array(cpu) / 1e3
    return {"world": name, "numba": numba and HAVE_NUMBA, "cycles": len(times),
            "beams": LidarParams().beams,
            "p50_us": _r(np.percentile(us, 50)), "p99_us": _r(np.percentile(us, 99)),
            "max_us": _r(us.max()), "cpu_p50_us": _r(np.percentile(cpu_us, 50)),
            "cpu_p99_us": _r(np.percentile(cpu_us, 99)),
            "pos_err_mean_m": _r3(np.mean(pos)) if pos else None,
            "pos_err_p95_m": _r3(np.percentile(pos, 95)) if pos else None,
            "vel_err_mean_mps": _r3(np.mean(vel)) if vel else None,
            "vel_err_p95_mps": _r3(np.percentile(vel, 95)) if vel else None,
            "coverage": _r3(near_hit / near_total) if near_total else None,
            "false_tracks": _r3(tracks_false / tracks_total) if tracks_total else None,
            "load_avg": round(os.getloadavg()[0], 2)}


def _r(x) -> float:
    return round(float(x), 1)


def _r3(x) -> float:
    return round(float(x), 3)


def main() -> None:
    ap = ArgumentParser(prog="papf bench tracker", description=plain(__doc__.split("\n")[0]))
    ap.add_argument("--world", action="append", help="world (repeatable; default: every road-*)")
    ap.add_argument("--seconds", type=float, default=30.0, help="sim time per world (30)")
    ap.add_argument("--match", type=float, default=1.0, help="track-to-truth match radius [m]")
    ap.add_argument("--seed", type=int, default=0, help="LiDAR noise seed (0)")
    ap.add_argument("--no-numba", action="store_true", help="numpy clustering, not the numba pass")
    ap.add_argument("--csv", type=Path, help="also append the rows to this CSV file")
    args = ap.parse_args()
    names = args.world or [w for w in packaged_worlds() if w.startswith("road-")]
    print(json.dumps({"machine": platform.processor() or platform.machine(),
                      "python": platform.python_version(), "cpus": os.cpu_count()}))
    for name in names:
        row = run_world(name, args.seconds, args.match, args.seed, not args.no_numba)
        print(json.dumps({"bench": "tracker", **row}), flush=True)
        if args.csv is not None:
            write_rows(args.csv, list(row), [row], append=True)


if __name__ == "__main__":
    main()
