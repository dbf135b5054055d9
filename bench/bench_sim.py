"""Speed of the simulation: sim time / wall time, printed as JSON lines.

Full stack (default): ``papf run --world W --planner P --seed S`` for each ``--planners``
(router, driver, LiDAR, planner, energy meter, the launcher itself; start-up and
shut-down included, like the ``wall_time_s`` of ``papf run``), with the CPU seconds of
every process (its Python threads and Zenoh's) sampled from /proc — where a cycle's time
goes. ``--repeat N`` runs each N times; every run is printed.

``--loop``: the lockstep loop alone — ``nodes.base_driver`` (sim) and ``nodes.lidar_sim``
as processes, every scan answered here with a constant Twist of the same stamp (a
trivial planner), ``--sim-s`` seconds of sim time after ``run_started``.

    papf bench sim [--planners apf,papf] [--world energy] [--seed 1] [--repeat 1]
    papf bench sim --loop [--sim-s 30] [--world energy] [--beams 300]
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import sys
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import zenoh  # noqa: E402

from common.ports import plain  # noqa: E402
from common.transport import wait_alive, zenoh_config  # noqa: E402
from papf.supervisor import Supervisor, free_port, wait_port  # noqa: E402
from schemas import Keys  # noqa: E402
from schemas.messages import Clock, Event, Scan, Twist  # noqa: E402


def bench(sim_s: float, world: str, beams: int) -> dict:
    keys = Keys("rosbot")
    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    py = sys.executable
    with Supervisor(show=lambda *_: False) as sup:
        sup.start("router", [py, "-m", "papf.router", "--listen", endpoint])
        if not wait_port(port, 20):
            raise RuntimeError(f"router did not start on {endpoint}")
        common = ["--connect", endpoint, "--world", world]
        sup.start("base_driver", [py, "-m", "nodes.base_driver", *common])
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


def bench_stack(world: str, planner: str, seed: int, zenoh_mode: str) -> dict:
    from bench.proc_cpu import TreeCPU
    from papf.runner import RunConfig, run

    with TreeCPU() as cpu:
        res = run(RunConfig(world=world, planner=planner, seed=seed, progress=False,
                            zenoh_mode=zenoh_mode))
    procs = cpu.per_process()
    return {"bench": "sim_stack", "world": world, "planner": planner, "seed": seed,
            "zenoh_mode": zenoh_mode, "outcome": res.outcome, "sim_s": res.sim_time_s,
            "wall_s": round(res.wall_time_s, 3),
            "sim_over_wall": round(res.sim_time_s / max(res.wall_time_s, 1e-9), 2),
            "cpu_s": round(sum(p["cpu_s"] for p in procs.values()), 2), "processes": procs,
            "cpus": os.cpu_count()}


def main() -> None:
    parser = argparse.ArgumentParser(prog="papf bench sim", description=plain(__doc__.splitlines()[0]))
    parser.add_argument("--loop", action="store_true", help="the driver + LiDAR loop alone")
    parser.add_argument("--sim-s", type=float, default=30.0, help="--loop: sim seconds to run (30)")
    parser.add_argument("--world", default="energy")
    parser.add_argument("--beams", type=int, default=300, help="--loop: LiDAR beams (300)")
    parser.add_argument("--planners", default="apf,papf", help="full stack: planners (apf,papf)")
    parser.add_argument("--seed", type=int, default=1, help="full stack: seed (1)")
    parser.add_argument("--repeat", type=int, default=1, help="full stack: runs per planner (1)")
    parser.add_argument("--zenoh-mode", choices=("client", "peer"), default="peer",
                        help="full stack: the nodes' Zenoh mode (as papf run --zenoh-mode)")
    a = parser.parse_args()
    if a.loop:
        print(json.dumps(bench(a.sim_s, a.world, a.beams)))
        return
    logging.getLogger("papf.run").setLevel(logging.WARNING)
    for planner in a.planners.split(","):
        for _ in range(a.repeat):
            print(json.dumps(bench_stack(a.world, planner, a.seed, a.zenoh_mode)), flush=True)


if __name__ == "__main__":
    main()
