"""Rounds of the traffic test three times at once, counting lockstep stalls (docs/performance.md,
"The lockstep stall").

One round: ``pytest -n 3 --keep-duplicates tests/e2e/test_e2e_traffic.py`` (three times): 27
road runs with IAPF, nine at a time, on this machine's two cores. A stall is a run whose world
simulator waited its whole lockstep wait (30 s in the test) for a command; the run's
``faults`` then name every node's last stamps, and this records which partner of the held
scan the planner had not taken (``odom``, ``objects``).

    python bench/stall_rounds.py --rounds 10 --label L --csv docs/data/lockstep-stall.csv
    python bench/stall_rounds.py --from-logs DIR --label L --csv F   # rounds run before: r-<n>.log
    python bench/stall_rounds.py --summary docs/data/lockstep-stall.csv   # -> …-summary.csv

A row per round: label, round, tests passed/failed, stalls, the held stamps and the planner's
missing partners, wall seconds, the 1-minute load before the round.
"""

from __future__ import annotations

import argparse
import csv
import os
import re
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bench.csvrows import emit, replace_label, write_rows  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
TEST = "tests/e2e/test_e2e_traffic.py"
FIELDS = ("label", "round", "passed", "failed", "stalls", "held_at_s", "missing", "wall_s",
          "load_avg_1min")
SUMMARY = ("label", "rounds", "rounds_stalled", "stalls", "runs", "missing_odom", "missing_objects")
RUNS_PER_ROUND = 27   # three tests of nine road runs
HELD = re.compile(r"base_driver at ([0-9.]+) s: no cmd_vel with stamp_ns=\d+ within")
PLANNER = re.compile(r"planner \(\d+ peer links\) took ([^;|\]]*)")


def parse(text: str) -> dict:
    """The counts of one round's pytest output: tests, stalls, what the planner missed."""
    passed = re.search(r"(\d+) passed", text)
    failed = re.search(r"(\d+) failed", text)
    held, missing = [], []
    for line in text.splitlines():
        m = HELD.search(line)
        if m and "the nodes' last stamps" in line:
            held.append(f"{float(m.group(1)):.2f}")
            missing.append(_missed(line, float(m.group(1))))
    return {"passed": int(passed.group(1)) if passed else 0,
            "failed": int(failed.group(1)) if failed else 0,
            "stalls": len(held), "held_at_s": " ".join(held), "missing": " ".join(missing)}


def _missed(line: str, t: float) -> str:
    """The topics whose last stamp the planner took is older than the held instant ``t``."""
    took = PLANNER.search(line)
    stamps = dict(part.strip().rsplit(" ", 1) for part in took.group(1).split(",")) if took else {}
    return "+".join(k for k in ("odom", "objects", "scan")
                    if k in stamps and float(stamps[k]) < t - 1e-6) or "?"


def summarise(path: Path) -> Path:
    """Per label of the rounds' CSV: rounds, rounds with a stall, stalls, runs, what was missed
    (``<name>-summary.csv`` beside it, written whole: it is derived from the rounds' CSV)."""
    with path.open(newline="") as fh:
        rows = list(csv.DictReader(fh))
    out = []
    for label in dict.fromkeys(r["label"] for r in rows):
        mine = [r for r in rows if r["label"] == label]
        missed = " ".join(r["missing"] for r in mine).split()
        out.append({"label": label, "rounds": len(mine),
                     "rounds_stalled": sum(int(r["stalls"]) > 0 for r in mine),
                     "stalls": sum(int(r["stalls"]) for r in mine),
                     "runs": RUNS_PER_ROUND * len(mine),
                     "missing_odom": missed.count("odom"), "missing_objects": missed.count("objects")})
    summary = path.with_name(path.stem + "-summary.csv")
    write_rows(summary, SUMMARY, out)
    return summary


def run_round() -> tuple[str, float]:
    t0 = time.monotonic()
    proc = subprocess.run([sys.executable, "-m", "pytest", "-q", "-n", "3", "-p", "no:cacheprovider",
                           "--keep-duplicates", TEST, TEST, TEST], cwd=ROOT, text=True,
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=1800)
    return proc.stdout, time.monotonic() - t0


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=10)
    ap.add_argument("--from-logs", type=Path, help="parse r-<n>.log files instead of running")
    ap.add_argument("--label")
    ap.add_argument("--summary", type=Path, help="summarise this rounds' CSV per label")
    ap.add_argument("--csv", type=Path)
    args = ap.parse_args(argv)
    if args.summary:
        print(summarise(args.summary))
        return
    if not args.label:
        ap.error("--label is required")
    rows: list[dict] = []
    if args.from_logs:   # rounds a loop of the same pytest command ran: its r-<n>.log files
        for log in sorted(args.from_logs.glob("r-*.log"), key=lambda p: int(p.stem[2:])):
            emit(rows, {"round": int(log.stem[2:]), **parse(log.read_text())}, args.label)
    else:
        for k in range(args.rounds):
            load = os.getloadavg()[0]
            text, wall = run_round()
            emit(rows, {"round": k + 1, **parse(text), "wall_s": round(wall, 1),
                        "load_avg_1min": round(load, 2)}, args.label)
    if args.csv:
        replace_label(args.csv, FIELDS, args.label, rows)


if __name__ == "__main__":
    main()
