"""Before/after ``papf run``, alternated: ``papf bench run_ab --before DIR [options]``.

Runs the whole command ``python -m papf run --world W --planner P --seed S --json`` with
this tree's code (or ``--after DIR``'s) and with another checkout's (``--before DIR``, e.g.
``git worktree add /tmp/old COMMIT``), one after the other in turns (before, after, before, …), so the load
of other jobs on a shared machine falls on both sides alike. Per run: the command's wall
time from start to exit (interpreter start-up, imports, start-up and shut-down of every
process included), the run's own ``wall_time_s`` from its JSON, the CPU seconds of the
command and every process it started (``RUSAGE_CHILDREN``), and each process's own CPU
seconds (from /proc, :class:`bench.proc_cpu.TreeCPU`; ``--procs-csv`` writes their medians
per side, planner and process, with the CPU per 100 ms cycle of sim time). ``--timeout 0.2`` times
start-up and shut-down alone. Prints one JSON line per run and one summary per side and
planner (medians and minima; whether every run of both sides gave the same figures) and writes the
summaries with ``--csv``. Speed is reported, never asserted.
"""

from __future__ import annotations

import json
import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

from bench.csvrows import check_csv, write_rows
from bench.proc_cpu import TreeCPU
from common.cliparse import ArgumentParser
from common.outfiles import append_jsonl

HERE = Path(__file__).resolve().parent
FIELDS = ("date", "code", "planner", "seed", "timeout_s", "runs", "command_wall_med_s",
          "command_wall_min_s", "run_wall_med_s", "run_wall_min_s", "cpu_med_s", "cpu_min_s", "sim_s",
          "sim_over_wall_med", "sim_over_run_wall_med", "cpu_ms_per_cycle", "same_figures",
          "load_min", "load_max")
PROC_FIELDS = ("date", "code", "planner", "seed", "timeout_s", "runs", "process", "cpu_med_s",
               "cpu_ms_per_cycle", "load_min", "load_max")
CYCLE_S = 0.1   # [s sim] one lockstep cycle (the LiDAR's scan period)


def one_run(tree: Path, planner: str, world: str, seed: int, timeout_s: float, port: int) -> dict:
    """One ``papf run`` of ``tree``'s code; wall and CPU of the command and its processes."""
    env = {**os.environ, "PYTHONPATH": str(tree)}
    cmd = [sys.executable, "-m", "papf", "run", "--world", world, "--planner", planner,
           "--seed", str(seed), "--json", "--port", str(port), "--timeout", f"{timeout_s:g}"]
    load = os.getloadavg()[0]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    with TreeCPU() as tree_cpu:
        out = subprocess.run(cmd, cwd=tree, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    lines = [x for x in out.stdout.splitlines() if x.startswith("{")]
    if not lines:
        raise SystemExit(f"bench run_ab: {tree}: no JSON from papf run (exit {out.returncode}): "
                         f"{out.stderr.strip().splitlines()[-1:]}")
    res = json.loads(lines[-1])
    res.pop("run_id", None)   # a new id each run, by design: not a figure
    return {"bench": "run_ab_run", "tree": str(tree), "planner": planner, "timeout_s": timeout_s,
            "command_wall_s": round(wall, 3), "run_wall_s": res.pop("wall_time_s"),
            "cpu_s": round(cpu, 3), "load_1min": load, "figures": res,
            "processes": {name: p["cpu_s"] for name, p in tree_cpu.per_process().items()
                          if name != "launcher"}}   # "launcher": this bench's own process


def summary(label: str, runs: list[dict], reference: dict | None = None) -> dict:
    """Medians and minima of one side's runs; ``same_figures``: every run gave the figures of
    ``reference`` (the first run of the planner on either side; default: this side's first)."""
    med, low = statistics.median, min
    reference = runs[0]["figures"] if reference is None else reference
    walls, inner, cpus = ([r[k] for r in runs] for k in ("command_wall_s", "run_wall_s", "cpu_s"))
    sim = runs[0]["figures"]["sim_time_s"]
    return {"date": time.strftime("%Y-%m-%dT%H:%M"), "code": label, "planner": runs[0]["planner"],
            "seed": runs[0]["figures"].get("seed"), "timeout_s": runs[0]["timeout_s"],
            "runs": len(runs),
            "command_wall_med_s": round(med(walls), 2), "command_wall_min_s": round(low(walls), 2),
            "run_wall_med_s": round(med(inner), 2), "run_wall_min_s": round(low(inner), 2),
            "cpu_med_s": round(med(cpus), 2), "cpu_min_s": round(low(cpus), 2), "sim_s": sim,
            "sim_over_wall_med": round(sim / med(walls), 1),
            "sim_over_run_wall_med": round(sim / med(inner), 1),   # the JSON's wall_time_s
            "cpu_ms_per_cycle": round(1e3 * med(cpus) / max(sim / CYCLE_S, 1.0), 2),
            "same_figures": all(r["figures"] == reference for r in runs),
            "load_min": round(min(r["load_1min"] for r in runs), 1),
            "load_max": round(max(r["load_1min"] for r in runs), 1)}


def process_rows(label: str, runs: list[dict]) -> list[dict]:
    """Median CPU seconds of each process over ``runs`` (0 in a run it did not start)."""
    head = summary(label, runs)
    cycles = max(head["sim_s"] / CYCLE_S, 1.0)
    names = sorted({n for r in runs for n in r["processes"]})
    rows = []
    for name in names:
        cpu = statistics.median(r["processes"].get(name, 0.0) for r in runs)
        rows.append({**{k: head[k] for k in ("date", "code", "planner", "seed", "timeout_s", "runs",
                                              "load_min", "load_max")},
                     "process": _short(name), "cpu_med_s": round(cpu, 2),
                     "cpu_ms_per_cycle": round(1e3 * cpu / cycles, 2)})
    return sorted(rows, key=lambda r: -r["cpu_med_s"])


def _short(name: str) -> str:
    """``nodes.world_sim`` -> ``world_sim``; ``papf`` (the command itself) -> ``launcher``. A
    checkout from before the world simulator had its own node runs it as ``nodes.base_driver``:
    its rows say ``base_driver``."""
    return "launcher" if name == "papf" else name.removeprefix("nodes.").removeprefix("papf.")


def main() -> None:
    parser = ArgumentParser(prog="papf bench run_ab", description=__doc__.splitlines()[0])
    parser.add_argument("--before", type=Path, required=True, help="the other checkout (its root)")
    parser.add_argument("--after", type=Path, default=HERE.parent,
                        help="the checkout measured as 'after' (default: this one)")
    parser.add_argument("--labels", default="before,after", help="the two sides' names (before,after)")
    parser.add_argument("--planners", default="apf,papf")
    parser.add_argument("--world", default="energy")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--rounds", type=int, default=3, help="runs per side and planner (3)")
    parser.add_argument("--timeout", type=float, default=300.0,
                        help="sim seconds at most (0.2: start-up and shut-down alone)")
    parser.add_argument("--port", type=int, default=17447, help="the runs' router port (17447)")
    parser.add_argument("--csv", type=Path, help="append the summaries to this CSV")
    parser.add_argument("--procs-csv", type=Path,
                        help="append each process's median CPU (per side and planner) to this CSV")
    parser.add_argument("--jsonl", type=Path, help="append every run's JSON line to this file")
    a = parser.parse_args()
    if a.csv:   # a foreign file: refused before the work, not after
        check_csv(a.csv, FIELDS)
    if a.procs_csv:
        check_csv(a.procs_csv, PROC_FIELDS)
    labels = a.labels.split(",")
    trees = (a.before, a.after)
    if not all((t / "papf" / "__main__.py").is_file() for t in trees) or len(labels) != 2 \
            or a.rounds < 1:
        parser.error("--before and --after must be checkouts (with papf/__main__.py), "
                     "--labels two names, --rounds >= 1")
    sides = ((labels[0], a.before.resolve()), (labels[1], a.after.resolve()))
    runs: dict[tuple[str, str], list[dict]] = {}
    for _ in range(a.rounds):
        for planner in a.planners.split(","):
            for label, tree in sides:
                r = one_run(tree, planner, a.world, a.seed, a.timeout, a.port)
                r["code"] = label
                runs.setdefault((label, planner), []).append(r)
                print(json.dumps(r), flush=True)
                if a.jsonl:
                    with append_jsonl(a.jsonl) as fh:   # JSON lines only, never a link
                        fh.write(json.dumps(r) + "\n")
    first = {}   # planner -> the figures of its first run (before): both sides must match
    for (_, planner), rs in runs.items():
        first.setdefault(planner, rs[0]["figures"])
    rows = [summary(label, rs, first[planner]) for (label, planner), rs in runs.items()]
    for row in rows:
        print(json.dumps({"bench": "run_ab", **row}), flush=True)
    if a.csv:
        write_rows(a.csv, FIELDS, rows, append=True)
    if a.procs_csv:
        write_rows(a.procs_csv, PROC_FIELDS,
                   [r for (label, _), rs in runs.items() for r in process_rows(label, rs)],
                   append=True)


if __name__ == "__main__":
    main()
