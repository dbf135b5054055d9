"""Driving over slow links, measured: ``papf bench link-drive`` (``python bench/bench_link_drive.py``).

For each planner x link (``papf link`` specs), one ``papf run --link SPEC --json`` on a
2.5 m corridor with a box beside the path (``v_max`` 0.5 m/s), real time: outcome, duration,
path, charge, and the robot's link figures (round trip p50/p99, commands obeyed and
refused, watchdog stops). ``--checkout DIR`` runs another checkout's code instead (its
directory first on ``PYTHONPATH``): the same runs before and after a change
(docs/link-driving.md "Measured"). Real-time runs on a loaded machine: the load average is
in every row. Prints one JSON object per run; ``--csv FILE`` appends them as rows.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from bench.csvrows import write_rows
from common.ports import plain

FIELDS = ["code", "planner", "link", "outcome", "duration_s", "path_length_m", "charge_mAh",
          "rtt_p50_ms", "rtt_p99_ms", "commands", "obeyed", "refused", "watchdog_stops",
          "reason", "wall_s", "load_avg", "machine"]
LINKS = ("delay=0", "delay=50,jitter=100", "delay=200,jitter=150", "delay=400,jitter=200",
         "delay=600,jitter=200")
WORLD = """name = "corridor"
description = "2.5 m ahead, a box beside the path"
[robot]
start = [0.0, 0.0, 0.0]
[goal]
position = [2.5, 0.0]
tolerance = 0.15
[[obstacles]]
kind = "box"
center = [1.2, 0.7]
size = [0.3, 0.3]
"""


def one_run(planner: str, link: str, world: Path, checkout: str | None, timeout_s: float,
            tag: str) -> dict:
    env = dict(os.environ)
    if checkout:
        env["PYTHONPATH"] = os.pathsep.join([checkout, env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    argv = [sys.executable, "-m", "papf", "run", "--world", str(world), "--planner", planner,
            "--link", link, "--json", "--set", "v_max=0.5", "--timeout", str(timeout_s),
            "--namespace", f"bench_ld_{os.getpid()}"]
    t0 = time.monotonic()
    out = subprocess.run(argv, capture_output=True, text=True, env=env, cwd=world.parent,
                         timeout=timeout_s * 4 + 120)
    wall = time.monotonic() - t0
    try:
        res = json.loads(out.stdout.strip().splitlines()[-1])
    except (IndexError, ValueError):
        res = {"outcome": "error", "reason": out.stderr.strip().splitlines()[-1:]}
    lk = res.get("link") or {}
    robot_side = (res.get("link_emulator") or {}).get("robot_side") or {}
    refused = (lk.get("late_commands") or 0) + (lk.get("stale_commands") or 0) if lk else \
        robot_side.get("late_commands")
    return {"code": tag, "planner": planner, "link": link, "outcome": res.get("outcome"),
            "duration_s": res.get("duration_s"), "path_length_m": res.get("path_length_m"),
            "charge_mAh": res.get("charge_mAh"), "rtt_p50_ms": lk.get("rtt_p50_ms"),
            "rtt_p99_ms": lk.get("rtt_p99_ms"), "commands": lk.get("commands"),
            "obeyed": lk.get("obeyed_commands"), "refused": refused,
            "watchdog_stops": robot_side.get("watchdog_stops"),
            "reason": str(res.get("reason", ""))[:160], "wall_s": round(wall, 1),
            "load_avg": round(os.getloadavg()[0], 2), "machine": platform.node()}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="papf bench link-drive", description=plain(__doc__),
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--planners", default="apf,papf")
    ap.add_argument("--links", default=";".join(LINKS), help="';'-separated papf link specs")
    ap.add_argument("--checkout", metavar="DIR", help="run this checkout's code instead")
    ap.add_argument("--tag", default="", help="the 'code' column (default: this or DIR's name)")
    ap.add_argument("--timeout", type=float, default=40.0, help="run-time limit per run [s]")
    ap.add_argument("--csv", metavar="FILE", help="append the rows to this CSV")
    args = ap.parse_args(argv)
    if args.checkout and not Path(args.checkout, "papf").is_dir():
        raise SystemExit(f"--checkout {args.checkout!r} has no papf/ package")
    tag = args.tag or (Path(args.checkout).name if args.checkout else "this")
    rows = []
    with tempfile.TemporaryDirectory(prefix="papf-bench-ld-") as tmp:
        world = Path(tmp) / "corridor.toml"
        world.write_text(WORLD)
        for link in [s for s in args.links.split(";") if s]:
            for planner in args.planners.split(","):
                row = one_run(planner, link, world, args.checkout, args.timeout, tag)
                print(json.dumps(row), flush=True)
                rows.append(row)
    if args.csv:
        write_rows(args.csv, FIELDS, rows, append=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
