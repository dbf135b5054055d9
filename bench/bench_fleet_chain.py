"""Where a lockstep fleet cycle's wall time goes, read from a recording of the run
(docs/performance.md "A fleet cycle, step by step").

The recorder stamps every sample with the wall time it arrived (MCAP ``publish_time``) beside
its sim stamp (``log_time``). For each lockstep instant of sim time from ``--from-s`` on, the
cycle starts when the world simulator's first ``<robot>/sim/bodies`` of it arrives, and this
gives, in milliseconds after that start, when the simulator's burst of the instant was out
(its last ``clock``), when the first and the last robot's ``scan`` and ``cmd_vel`` of the
instant came, and when the next instant's burst began: the median and the 90th percentile
over the instants.

    papf run --world F --planner apf --record run.mcap --timeout 30   # F: a fleet world
    papf bench fleet-chain run.mcap --label L [--csv docs/data/fleet-chain.csv]

The recorder is one more subscriber of every topic: its own work shares the machine with the
run it measures (figures are the run's with a recorder, compared with each other).
"""

from __future__ import annotations

import argparse
import statistics
import sys
from collections import defaultdict
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bench.csvrows import check_csv, emit, replace_label  # noqa: E402
from common.errors import PapfError  # noqa: E402
from papf.recording.reader import open_recording  # noqa: E402

FIELDS = ("label", "phase", "median_ms", "p90_ms", "instants")
PHASES = (("burst out", "clock", max), ("first scan", "scan", min), ("last scan", "scan", max),
          ("first cmd_vel", "cmd_vel", min), ("last cmd_vel", "cmd_vel", max))


def arrivals(path: Path) -> dict[int, dict[str, list[int]]]:
    """sim stamp [ns] -> topic kind (``scan``: every robot's ``<robot>/scan``) -> wall times
    [ns] of its samples' arrival (RecordingError: not a whole MCAP recording)."""
    found: dict[int, dict[str, list[int]]] = defaultdict(lambda: defaultdict(list))
    with open_recording(path) as rec:
        for raw in rec.raw(log_time_order=False):
            _robot, _, kind = raw.key.partition("/")
            found[raw.log_time_ns][kind].append(raw.publish_time_ns)
    return found


def phases(found: dict[int, dict[str, list[int]]], from_ns: int) -> dict[str, list[float]]:
    """Each phase's times [ms] after its cycle's start, one per instant that has a next one."""
    stamps = sorted(t for t, kinds in found.items() if t >= from_ns and kinds.get("sim/bodies"))
    out: dict[str, list[float]] = defaultdict(list)
    for now, after in zip(stamps, stamps[1:], strict=False):
        kinds, start = found[now], min(found[now]["sim/bodies"])
        for name, kind, pick in PHASES:
            if kinds.get(kind):
                out[name].append((pick(kinds[kind]) - start) / 1e6)
        out["next burst"].append((min(found[after]["sim/bodies"]) - start) / 1e6)
    return out


def rows(out: dict[str, list[float]]) -> list[dict]:
    return [{"phase": name, "median_ms": round(statistics.median(v), 2),
             "p90_ms": round(sorted(v)[int(0.9 * (len(v) - 1))], 2), "instants": len(v)}
            for name, v in out.items() if v]


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(prog="papf bench fleet-chain", description=__doc__.split("\n\n")[0])
    parser.add_argument("recording", type=Path, help="MCAP of a lockstep fleet run (papf run --record)")
    parser.add_argument("--from-s", type=float, default=1.0, help="sim time [s] to start at (default 1)")
    parser.add_argument("--label", default="", help="the rows' label (with --csv: replaces that label's)")
    parser.add_argument("--csv", type=Path, help="write the rows to this CSV")
    args = parser.parse_args(argv)
    if not args.recording.is_file():
        parser.error(f"{args.recording}: no such recording")
    if args.csv:
        check_csv(args.csv, FIELDS)   # a table of this benchmark or a new file, before the work
    found = phases(arrivals(args.recording), round(args.from_s * 1e9))
    if not found:
        parser.error(f"{args.recording}: no lockstep fleet instants (no <robot>/sim/bodies) "
                     f"after {args.from_s:g} s")
    kept: list[dict] = []
    for row in rows(found):
        emit(kept, row, args.label)
    if args.csv:
        replace_label(args.csv, FIELDS, args.label, [{k: v for k, v in r.items() if k != "label"}
                                                     for r in kept])


if __name__ == "__main__":
    try:
        main()
    except PapfError as exc:   # a damaged recording, a CSV that is not this table: one line
        raise SystemExit(str(exc)) from None
