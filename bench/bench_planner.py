"""Planner cycle time on synthetic 300-point scans: ``python bench/bench_planner.py [--cycles N]``.

Prints one JSON object per (planner, scene) with the time of ``Planner.step`` (scan
conversion + algorithm + messages) in microseconds: wall time p50, p99, max, and the
thread's CPU time p50, p99 (less disturbed when other processes share the cores); and
``cmd_*``: the same up to the command (:meth:`Planner.command`: what the node publishes
first — the debug ``PlannerState`` is built after). Every registered planner is timed
on every scene. Scenes:

- ``open``: no returns (inf everywhere);
- ``energy``: the energy world's three obstacles seen from along the approach;
- ``trap``: the robot inside a ring of returns with one narrow gap, goal outside; every
  PAPF prediction stagnates, so with ``persist_quarks=false`` each cycle places all
  M = 10 top quarks and runs M + 1 predictions — the PAPF worst case;
- ``road``: a two-lane ROSbot road (0.6 m lanes) with three tracked vehicles near the robot
  (a slow leader, one in the other lane, one behind), handed over as obstacle tracks; IAPF
  (which needs the road and the tracks) runs only here, with its F_step = 20 prediction.

PAPF is also timed with the numpy fallback (``use_numba=false``). Each row carries the
1-minute load average at its start and end: CPU time (the ``cpu_`` figures) is far less
disturbed than wall time when other jobs share the cores, but not immune. Speed is
reported, never asserted (tests/ do not time anything).

``--cases``/``--scenes`` keep some rows (``--cases papf_worst_numba --scenes trap``: the
PAPF worst case alone); ``--csv FILE`` writes the rows as CSV (``docs/data/bench-planner.csv``;
``make docs`` renders the table of docs/performance.md from it).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from bench.csvrows import check_csv, write_rows
from common.cliparse import ArgumentParser
from common.ports import plain
from nodes.planner.registry import PLANNERS, declared, make_planner, one_with_role
from nodes.planner.road import Track
from schemas.messages import Goal, Odometry
from worlds.toy import box_segments, cast_scan, toy_world

RING = toy_world(segments=tuple(
    (0.8 * math.cos(a0), 0.8 * math.sin(a0), 0.8 * math.cos(a1), 0.8 * math.sin(a1))
    for a0, a1 in zip(np.linspace(0.05, 2 * math.pi - 0.05, 41)[:-1],
                      np.linspace(0.05, 2 * math.pi - 0.05, 41)[1:], strict=True)))
ENERGY = toy_world(circles=((5.0, -0.2, 0.2),),
                  segments=box_segments(2.5, 0.1, 0.4, 0.4) + box_segments(7.5, 0.15, 0.05, 0.7))
SCENES = {  # world, start x range [m], goal
    "open": (toy_world(), (0.0, 2.0), (10.0, 0.0)),
    "energy": (ENERGY, (0.0, 2.0), (10.0, 0.0)),
    "trap": (RING, (-0.05, 0.05), (3.0, 0.0)),
    "road": (toy_world(), (0.0, 2.0), (10.0, 0.0)),
}
ROAD = dict(road_lanes=2, road_y_min=-0.3, road_lane_width=0.6)   # ROSbot-scale two-lane road
# vehicles relative to the robot: (dx, y, vx) [m, m, m/s], 0.5 x 0.3 m: a slow leader, one in
# the other lane, one behind (each within IAPF's safety distance: all fields evaluated)
ROAD_VEHICLES = ((1.0, 0.0, 0.1), (1.6, 0.6, 0.2), (-0.8, 0.0, 0.25))
ONLY = dict.fromkeys(declared("uses_objects"), ("road",))   # the road and obstacle tracks (IAPF)
PAPF = one_with_role("papf-proposed")
CASES = [(name, name, []) for name in sorted(PLANNERS)] + [  # (label, planner, --set overrides)
    (f"{PAPF}_worst_numba", PAPF, ["persist_quarks=false"]),
    (f"{PAPF}_worst_numpy", PAPF, ["persist_quarks=false", "use_numba=false"]),
]


def road_tracks(x: float) -> list:
    """The road scene's vehicles as obstacle tracks for a robot at ``x`` [m]."""
    return [Track(x + dx, y, 0.0, vx, 0.0, 0.5, 0.3, i) for i, (dx, y, vx) in enumerate(ROAD_VEHICLES)]


CSV_FIELDS = ("date", "code", "case", "planner", "scene", "cycles", "max_debug_points", "cmd_cpu_p50_us",
              "cmd_cpu_p99_us", "cpu_p50_us", "cpu_p99_us", "cmd_p50_us", "cmd_p99_us", "p50_us",
              "p99_us", "load_start", "load_end")


def bench(planner_name: str, sets: list[str], scene: str, cycles: int) -> dict:
    load_start = os.getloadavg()[0]
    world, (x0, x1), goal = SCENES[scene]
    planner = make_planner(planner_name, sets=sets)
    xs = np.linspace(x0, x1, cycles)
    scans = [cast_scan(world, x, 0.0, 0.0, stamp_ns=k) for k, x in enumerate(xs)]
    odoms = [Odometry(stamp_ns=k, x=x, y=0.0, yaw=0.0, v=0.0, w=0.0) for k, x in enumerate(xs)]
    road = ROAD if scene == "road" else {}
    planner.set_goal(Goal(stamp_ns=0, x=goal[0], y=goal[1], **road))
    planner.step(scans[0], odoms[0])                     # warm-up (JIT compile)
    times, cpu, cmd_times, cmd_cpu, quarks = [], [], [], [], 0
    for scan, odom in zip(scans, odoms, strict=True):
        planner.set_goal(Goal(stamp_ns=0, x=goal[0], y=goal[1], **road))
        planner.state = "driving"                          # keep timing the algorithm
        if road:
            planner.set_objects(road_tracks(odom.x))
        t0, c0 = time.perf_counter_ns(), time.thread_time_ns()
        _, finish = planner.command(scan, odom)
        t1, c1 = time.perf_counter_ns(), time.thread_time_ns()
        state, _ = finish()
        times.append(time.perf_counter_ns() - t0)
        cpu.append(time.thread_time_ns() - c0)
        cmd_times.append(t1 - t0)
        cmd_cpu.append(c1 - c0)
        quarks = max([quarks, *(len(d.points) for d in state.debug if d.kind == "points")])
    out = {"planner": planner_name, "settings": sets, "scene": scene, "cycles": cycles,
           "beams": int(scans[0].ranges.size), "max_debug_points": quarks,
           "load_start": round(load_start, 1), "load_end": round(os.getloadavg()[0], 1)}
    for prefix, wall, thread in (("", times, cpu), ("cmd_", cmd_times, cmd_cpu)):
        us, cpu_us = np.array(wall) / 1e3, np.array(thread) / 1e3
        out.update({f"{prefix}p50_us": _r(np.percentile(us, 50)),
                    f"{prefix}p99_us": _r(np.percentile(us, 99)), f"{prefix}max_us": _r(us.max()),
                    f"{prefix}cpu_p50_us": _r(np.percentile(cpu_us, 50)),
                    f"{prefix}cpu_p99_us": _r(np.percentile(cpu_us, 99))})
    return out


def _r(x) -> float:
    return round(float(x), 1)


def main() -> None:
    ap = ArgumentParser(prog="papf bench planner", description=plain(__doc__.split("\n")[0]))
    ap.add_argument("--cycles", type=int, default=300, help="cycles per row (300; numpy rows a tenth)")
    ap.add_argument("--cases", help="comma-separated case labels to keep (default: all): "
                    + ", ".join(label for label, _n, _s in CASES))
    ap.add_argument("--scenes", help="comma-separated scenes to keep (default: all): " + ", ".join(SCENES))
    ap.add_argument("--csv", type=Path, help="also write the rows to this CSV file")
    ap.add_argument("--append", action="store_true", help="add the rows to --csv instead of replacing it")
    ap.add_argument("--label", default=None,
                    help="the 'code' column (default: the git commit of this tree, if any)")
    args = ap.parse_args()
    if args.csv:   # a foreign file: refused before the work, not after
        check_csv(args.csv, CSV_FIELDS)
    cases = _pick(ap, "--cases", args.cases, [label for label, _n, _s in CASES])
    scenes = _pick(ap, "--scenes", args.scenes, list(SCENES))
    if args.cycles < 1:
        ap.error("--cycles must be >= 1")
    print(json.dumps({"machine": platform.processor() or platform.machine(),
                      "python": platform.python_version()}))
    for line in left_out(cases, scenes):   # a case the scenes exclude is named, not dropped
        print(line, file=sys.stderr, flush=True)
    rows = []
    for label, name, sets in CASES:
        for scene in ONLY.get(name, SCENES):
            if label not in cases or scene not in scenes:
                continue
            cycles = args.cycles if "numpy" not in label else max(20, args.cycles // 10)
            rows.append({"case": label, **bench(name, sets, scene, cycles)})
            print(json.dumps(rows[-1]), flush=True)
    if args.csv:
        code = _commit() if args.label is None else args.label
        date = time.strftime("%Y-%m-%dT%H:%M", time.gmtime())
        write_rows(args.csv, CSV_FIELDS, ({"date": date, "code": code, **row} for row in rows),
                   append=args.append)


def _commit() -> str:
    """Short git commit of the tree this bench runs from ("" outside a git checkout)."""
    try:
        done = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                              text=True, cwd=Path(__file__).parent, timeout=10)
    except (OSError, subprocess.SubprocessError):
        return ""
    return done.stdout.strip() if done.returncode == 0 else ""


def left_out(cases: list[str], scenes: list[str]) -> list[str]:
    """One line per kept case that none of ``scenes`` can run, and why."""
    out = []
    for label, name, _sets in CASES:
        only = ONLY.get(name)
        if label in cases and only and not set(only) & set(scenes):
            out.append(f"bench planner: {label} left out: it runs only on scene(s) "
                       f"{', '.join(only)} (IAPF needs a road and obstacle tracks); "
                       f"add --scenes {','.join(only)}")
    return out


def _pick(ap: argparse.ArgumentParser, option: str, text: str | None, valid: list[str]) -> list[str]:
    if text is None:
        return valid
    picked = [x.strip() for x in text.split(",") if x.strip()]
    bad = [x for x in picked if x not in valid]
    if bad or not picked:
        ap.error(f"{option} {text!r}: valid values are {', '.join(valid)}")
    return picked


if __name__ == "__main__":
    main()
