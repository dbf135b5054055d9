"""Speed of the simulation: sim time / wall time, printed as JSON lines.

Full stack (default): ``papf run --world W --planner P --seed S`` for each ``--planners``
(every node and the launcher with its embedded router; start-up and shut-down included,
like the ``wall_time_s`` of ``papf run``), with the CPU seconds of every process (its
Python threads and Zenoh's) sampled from /proc — where a cycle's time goes, and a figure
far less disturbed than wall time when other work shares the cores. ``--repeat N`` runs
each N times; every run is printed, then one ``sim_stack_min`` line per planner: the
minimum over the runs of the wall time and of each process's CPU seconds (and whether
every run gave the same figures). ``--csv FILE --label L`` also writes those minima as
rows labelled ``L`` (rows of other labels in FILE are kept: a before/after table).
``--timeout 0.2`` measures start-up and shut-down alone. ``--summarize FILE`` takes the
run lines of earlier invocations from FILE instead of running (e.g. runs alternated with
another checkout, so both see the same load) and prints and writes their minima.

``--floor``: the same lockstep chain in one process without the bus (``bench/sim_floor.py``):
CPU microseconds per 100 ms cycle of physics, ray cast, planner, meter, encoding and
decoding, and one Zenoh hop between two processes — what a run costs before any
transport; ``--csv FILE`` writes those parts (one row per planner and part).

``--loop``: the lockstep loop alone — ``nodes.world_sim`` and ``nodes.lidar_sim``
as processes, every scan answered here with a constant Twist of the same stamp (a
trivial planner), ``--sim-s`` seconds of sim time after ``run_started``.

    papf bench sim [--planners apf,papf] [--world energy] [--seed 1] [--repeat 1]
                   [--timeout 300] [--csv FILE --label L] [--summarize RUNS.jsonl]
    papf bench sim --loop [--sim-s 30] [--world energy] [--beams 300]
    papf bench sim --floor [--planners apf,papf] [--csv FILE]
"""

from __future__ import annotations

import json
import logging
import os
import sys
import threading
import time
from pathlib import Path

from common.cliparse import ArgumentParser

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import zenoh  # noqa: E402

from bench.csvrows import check_csv, replace_label  # noqa: E402
from common.ports import plain  # noqa: E402
from common.transport import wait_alive, zenoh_config  # noqa: E402
from papf.launch.supervisor import Supervisor, free_port, wait_port  # noqa: E402
from schemas import Keys  # noqa: E402
from schemas.messages import Clock, Event, Scan, Twist  # noqa: E402
from worlds import load_world  # noqa: E402


def bench(sim_s: float, world: str, beams: int) -> dict:
    keys = Keys("rosbot")
    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    py = sys.executable
    with Supervisor(show=lambda *_: False) as sup:
        sup.start("router", [py, "-m", "papf.launch.router", "--listen", endpoint])
        if not wait_port(port, 20):
            raise RuntimeError(f"router did not start on {endpoint}")
        common = ["--connect", endpoint, "--world", world]
        sup.start("base_driver", [py, "-m", "nodes.world_sim", *common])
        sup.start("lidar_sim", [py, "-m", "nodes.lidar_sim", *common, "--beams", str(beams)])
        with zenoh.open(zenoh_config("client", [endpoint])) as session:
            missing = wait_alive(session, keys, ["base_driver", "lidar_sim"], 60,
                                 abort=lambda: bool(sup.dead()))
            if missing:
                raise RuntimeError(f"nodes not alive: {missing}")
            cmd = session.declare_publisher(keys.cmd_vel)
            done = threading.Event()
            end_ns = int(sim_s * 1e9)
            scans = [0]
            lock = threading.Lock()

            def on_scan(sample):  # the trivial planner
                scan = Scan.from_bytes(sample.payload.to_bytes())
                with lock:  # no put while the publisher is undeclared below
                    if not done.is_set():
                        scans[0] += 1
                        cmd.put(Twist(stamp_ns=scan.stamp_ns, v=0.3, w=0.1).to_bytes())

            def on_clock(sample):
                if Clock.from_bytes(sample.payload.to_bytes()).stamp_ns >= end_ns:
                    done.set()

            subs = [session.declare_subscriber(keys.scan, on_scan),
                    session.declare_subscriber(keys.clock, on_clock)]
            t0 = time.perf_counter()
            session.put(keys.events, Event(stamp_ns=0, kind="run_started", source="bench").to_bytes())
            finished = done.wait(timeout=max(60.0, sim_s * 5))
            wall = time.perf_counter() - t0
            with lock:
                done.set()
            for sub in subs:
                sub.undeclare()
            cmd.undeclare()
    return {"bench": "sim_lockstep", "world": world, "beams": beams, "sim_s": sim_s,
            "wall_s": round(wall, 3), "sim_over_wall": round(sim_s / wall, 2),
            "scans_answered": scans[0], "finished": finished, "cpus": os.cpu_count()}


def bench_stack(world: str, planner: str, seed: int, zenoh_mode: str,
                timeout_s: float = 300.0) -> dict:
    from bench.proc_cpu import TreeCPU
    from papf.launch.run import RunConfig, run

    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else None
    with TreeCPU() as cpu:
        res = run(RunConfig(world=world, planner=planner, seed=seed, progress=False,
                            zenoh_mode=zenoh_mode, timeout_s=timeout_s))
    procs = cpu.per_process()
    figures = {k: v for k, v in res.to_json().items() if k != "wall_time_s"}
    return {"bench": "sim_stack", "world": world, "planner": planner, "seed": seed,
            "zenoh_mode": zenoh_mode, "outcome": res.outcome, "sim_s": res.sim_time_s,
            "wall_s": round(res.wall_time_s, 3),
            "sim_over_wall": round(res.sim_time_s / max(res.wall_time_s, 1e-9), 2),
            "cpu_s": round(sum(p["cpu_s"] for p in procs.values()), 2), "processes": procs,
            "load_1min": load, "cpus": os.cpu_count(), "figures": figures}


def minimum(runs: list[dict]) -> dict:
    """The minimum over repeated runs of one planner: wall time, each process's CPU."""
    best = min(runs, key=lambda r: r["wall_s"])
    names = sorted({n for r in runs for n in r["processes"]},
                   key=lambda n: -max(r["processes"].get(n, {}).get("cpu_s", 0) for r in runs))
    procs = {n: min(r["processes"][n]["cpu_s"] for r in runs if n in r["processes"])
             for n in names}
    return {"bench": "sim_stack_min", "world": best["world"], "planner": best["planner"],
            "seed": best["seed"], "zenoh_mode": best["zenoh_mode"], "runs": len(runs),
            "sim_s": best["sim_s"], "wall_s": best["wall_s"],
            "sim_over_wall": best["sim_over_wall"],
            "cpu_s": round(min(r["cpu_s"] for r in runs), 2), "processes": procs,
            "same_figures": all(r["figures"] == runs[0]["figures"] for r in runs),
            "load_1min": [r["load_1min"] for r in runs], "cpus": best["cpus"]}


CSV_FIELDS = ("label", "planner", "world", "seed", "runs", "process", "cpu_s", "wall_s",
              "sim_over_wall")


def write_csv(path: Path, label: str, summaries: list[dict]) -> None:
    """Rows of ``label`` (one per process, then ``all`` with the wall time) replace that
    label's rows in ``path``; other labels' rows stay."""
    rows = []
    for s in summaries:
        base = {"label": label, "planner": s["planner"], "world": s["world"], "seed": s["seed"],
                "runs": s["runs"]}
        rows += [{**base, "process": n.removeprefix("nodes."), "cpu_s": f"{c:.2f}"}
                 for n, c in s["processes"].items()]
        rows.append({**base, "process": "all", "cpu_s": f"{s['cpu_s']:.2f}",
                     "wall_s": f"{s['wall_s']:.2f}", "sim_over_wall": f"{s['sim_over_wall']:.1f}"})
    replace_label(path, CSV_FIELDS, label, rows)


def summarize(runs_file: Path, csv_path: Path | None, label: str | None) -> None:
    try:
        lines = runs_file.read_text().splitlines()
    except OSError as exc:
        sys.exit(f"bench sim: cannot read {runs_file}: {exc}")
    runs = [r for r in (json.loads(x) for x in lines if x.startswith("{"))
            if r.get("bench") == "sim_stack"]
    summaries = [minimum([r for r in runs if r["planner"] == p])
                 for p in dict.fromkeys(r["planner"] for r in runs)]
    for s in summaries:
        print(json.dumps(s))
    if csv_path:
        write_csv(csv_path, label, summaries)


FLOOR_FIELDS = ("label", "planner", "part", "cpu_s", "us_per_cycle")
CHAIN_PART = "chain: physics + outputs + cast + planner"


def floor(planners: list[str], world: str, seed: int, csv_path: Path | None,
          label: str | None = None) -> None:
    """The chain in one process; with ``csv_path``, its rows (labelled ``label``) replace
    that label's rows in the CSV, other labels' stay (e.g. alternated before/after rounds)."""
    from bench.sim_floor import chain, hop_latency

    rows = []
    for planner in planners:
        res = {"bench": "sim_floor", "world": world, "planner": planner, "seed": seed,
               **chain(world, planner, seed), "cpus": os.cpu_count()}
        print(json.dumps(res), flush=True)
        rows += [{"planner": planner, "part": part, "cpu_s": f"{res['cpu_s'][part]:.3f}",
                  "us_per_cycle": f"{us:.0f}"} for part, us in res["us_per_cycle"].items()]
        rows.append({"planner": planner, "part": CHAIN_PART,
                     "cpu_s": "", "us_per_cycle": f"{res['chain_us_per_cycle']:.0f}"})
    hop = {"bench": "zenoh_hop", **hop_latency(root=str(ROOT))}
    print(json.dumps(hop), flush=True)
    rows.append({"planner": "", "part": "one Zenoh hop (p50), 3 per cycle on the chain",
                 "cpu_s": "", "us_per_cycle": f"{hop['hop_us_p50']:.0f}"})
    if csv_path:
        replace_label(csv_path, FLOOR_FIELDS, label or "", rows)


def main() -> None:
    parser = ArgumentParser(prog="papf bench sim", description=plain(__doc__.splitlines()[0]))
    parser.add_argument("--loop", action="store_true", help="the driver + LiDAR loop alone")
    parser.add_argument("--floor", action="store_true",
                        help="the lockstep chain in one process, no bus (CPU per cycle per part)")
    parser.add_argument("--sim-s", type=float, default=30.0, help="--loop: sim seconds to run (30)")
    parser.add_argument("--world", default="energy")
    parser.add_argument("--beams", type=int, default=300, help="--loop: LiDAR beams (300)")
    parser.add_argument("--planners", default="apf,papf", help="full stack: planners (apf,papf)")
    parser.add_argument("--seed", type=int, default=1, help="full stack: seed (1)")
    parser.add_argument("--repeat", type=int, default=1, help="full stack: runs per planner (1)")
    parser.add_argument("--zenoh-mode", choices=("client", "peer"), default="peer",
                        help="full stack: the nodes' Zenoh mode (as papf run --zenoh-mode)")
    parser.add_argument("--timeout", type=float, default=300.0,
                        help="full stack: sim seconds at most (0.2: start-up and shut-down alone)")
    parser.add_argument("--csv", type=Path, help="full stack: write the minima here (with --label)")
    parser.add_argument("--label", help="the rows' label in --csv (e.g. before, after); with "
                        "--floor, rows of other labels in the CSV are kept")
    parser.add_argument("--summarize", type=Path, metavar="RUNS",
                        help="full stack: minima of the run lines in RUNS (JSON lines) instead of running")
    a = parser.parse_args()
    if a.csv:   # a foreign file: refused before the work, not after
        check_csv(a.csv, FLOOR_FIELDS if a.floor else CSV_FIELDS)
    if a.loop:
        print(json.dumps(bench(a.sim_s, a.world, a.beams)))
        return
    if a.floor:
        robots = len(load_world(a.world).robots)
        if robots > 1:   # the chain is one robot's: physics, its scan, its planner, its meter
            raise SystemExit(f"--floor runs one robot; {a.world!r} has {robots} "
                             "(papf bench fleet measures a fleet)")
        floor(a.planners.split(","), a.world, a.seed, a.csv, a.label)
        return
    if a.repeat < 1 or not a.timeout > 0 or bool(a.csv) != bool(a.label):
        parser.error("--repeat must be >= 1, --timeout > 0, and --csv and --label go together")
    if a.summarize:
        summarize(a.summarize, a.csv, a.label)
        return
    logging.getLogger("papf.run").setLevel(logging.WARNING)
    summaries = []
    for planner in a.planners.split(","):
        runs = []
        for _ in range(a.repeat):
            runs.append(bench_stack(a.world, planner, a.seed, a.zenoh_mode, a.timeout))
            print(json.dumps(runs[-1]), flush=True)
        summaries.append(minimum(runs))
        print(json.dumps(summaries[-1]), flush=True)
    if a.csv:
        write_csv(a.csv, a.label, summaries)


if __name__ == "__main__":
    main()
