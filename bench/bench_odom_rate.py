"""What a fleet's odometry rate changes in its figures: each world run to its outcome at each
rate (``papf run --odom-hz``), one row per robot.

A fleet's planners read odometry only at the scan instants, so the drive is the same at any
rate that divides the scan period (tests/unit/test_odom_rate.py); what the rate changes is
the energy meter's integration step, the outcome's time resolution and the path length's
chords. ``default`` is the run's own rate (a fleet's without people: the scan rate). After
each run's robots, a ``(fleet)`` row: how many reached, the longest duration, the closest
approach, the sums of the charges and of the path lengths.

    python bench/bench_odom_rate.py [--worlds fleet-ring-16] [--rates default,50]
        [--planner papf] [--timeout 120] [--csv docs/data/fleet-odom-energy.csv --label L]
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench.csvrows import emit, replace_label  # noqa: E402
from common.cliparse import ArgumentParser  # noqa: E402
from common.ports import plain  # noqa: E402
from papf.launch.supervisor import free_port  # noqa: E402

FIELDS = ("label", "world", "planner", "odom_hz", "robot", "outcome", "duration_s",
          "charge_mAh", "path_length_m", "min_separation_m", "wall_s")


def run_rows(world: str, planner: str, rate: str, timeout_s: float) -> list[dict]:
    """One ``papf run --json`` of ``world`` at ``rate`` (``default``: no ``--odom-hz``)."""
    argv = [sys.executable, "-m", "papf", "run", "--world", world, "--planner", planner,
            "--timeout", f"{timeout_s:g}", "--json", "--port", str(free_port()),
            *([] if rate == "default" else ["--odom-hz", rate])]
    proc = subprocess.run(argv, capture_output=True, text=True, check=False)
    lines = [ln for ln in proc.stdout.splitlines() if ln.startswith("{")]
    if not lines:
        raise SystemExit(f"bench odom rate: {world} at {rate}: no JSON (exit {proc.returncode}): "
                         f"{proc.stderr.strip().splitlines()[-1:]}")
    r = json.loads(lines[-1])
    each = [{"world": world, "planner": planner, "odom_hz": rate, "robot": x["name"],
             "outcome": x["outcome"], "duration_s": x["duration_s"], "charge_mAh": x["charge_mAh"],
             "path_length_m": x["path_length_m"], "min_separation_m": x["min_separation_m"],
             "wall_s": round(r["wall_time_s"], 2)} for x in r["robots"]]
    reached = sum(x["outcome"] == "reached" for x in r["robots"])
    fleet = {**each[0], "robot": "(fleet)", "outcome": f"{reached}/{len(each)} reached",
             "duration_s": r["duration_s"], "min_separation_m": r["min_separation_m"],
             "charge_mAh": round(sum(x["charge_mAh"] or 0.0 for x in each), 6),
             "path_length_m": round(sum(x["path_length_m"] for x in each), 6)}
    return [*each, fleet]


def main(argv=None) -> None:
    parser = ArgumentParser(prog="python bench/bench_odom_rate.py",
                            description=plain(__doc__.splitlines()[0]))
    parser.add_argument("--worlds", default="fleet-ring-16", help="fleet worlds")
    parser.add_argument("--rates", default="default,50",
                        help="odometry rates [Hz], 'default' for the run's own")
    parser.add_argument("--planner", default="papf", help="every robot's planner")
    parser.add_argument("--timeout", type=float, default=120.0, help="sim-time limit [s]")
    parser.add_argument("--csv", type=Path, help="write the rows here (with --label)")
    parser.add_argument("--label", help="the rows' label in --csv")
    args = parser.parse_args(argv)
    rows = []
    for world in [w for w in args.worlds.split(",") if w]:
        for rate in [r for r in args.rates.split(",") if r]:
            for row in run_rows(world, args.planner, rate, args.timeout):
                emit(rows, row, args.label)
    if args.csv:
        replace_label(args.csv, FIELDS, args.label, rows)


if __name__ == "__main__":
    main()
