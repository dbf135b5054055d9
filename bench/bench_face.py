"""The ROS 2 face's cost (``--ros-face``): the face node's CPU per planner cycle and added
latency, and a lockstep ``papf run`` with ``--ros-face`` against one without.

    papf bench face [--duration 10] [--runs 3] [--world papf-test-4] [--planner papf] [--csv F]

1. **Node**: router and ``python -m nodes.ros_face`` as processes; this process publishes the
   stack's traffic at its real rates (:func:`bench.bench_view.traffic`: scan, cmd_vel,
   planner state 10 Hz, odom 50 Hz …) for ``--duration`` s while a raw Zenoh subscriber
   takes the face's ``/scan``, ``/odom`` and ``/markers`` (rmw_zenoh keys). Reports the face's
   CPU share of one core, its CPU time per planner cycle (10 Hz: one scan, one state, five
   odometry samples) and the latency our key -> the face's rmw_zenoh key (p50/p99).
2. **Run**: ``papf run --json`` in lockstep, ``--runs`` times each without and with
   ``--ros-face`` (interleaved), wall time median and the difference per planner cycle.

Prints one JSON object; ``--csv F`` also writes its figures as rows (metric, value, unit).
Not a test: numbers depend on the machine and its load.
"""

from __future__ import annotations

import json
import statistics
import subprocess
import sys
import time
from pathlib import Path

import zenoh

from bench.bench_view import TICK_NS, cpu_s, percentiles, traffic
from bench.csvrows import check_csv, write_rows
from common import rmw_zenoh as rz
from common import ros2_convert as rc
from common.cliparse import ArgumentParser
from common.transport import wait_alive, zenoh_config
from nodes.planner.registry import one_with_role
from papf.launch.supervisor import Supervisor, free_port, wait_port
from schemas import Keys

KEYS = Keys("rosbot")
DOMAIN = 0
WATCHED = {"scan": rc.LASER_SCAN, "odom": rc.ODOMETRY, "markers": rc.MARKER_ARRAY}
CYCLE_HZ = 10.0       # planner cycles per second (one scan each)


def bench_node(duration_s: float) -> dict:
    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    with Supervisor(show=lambda n, line: "ERROR" in line) as sup:
        sup.start("router", [sys.executable, "-m", "papf.launch.router", "--listen", endpoint])
        assert wait_port(port, 15.0)
        face = sup.start("ros_face", [sys.executable, "-m", "nodes.ros_face", "--connect", endpoint,
                                      "--ros-domain", str(DOMAIN)])
        with zenoh.open(zenoh_config("client", [endpoint])) as session:
            assert not wait_alive(session, KEYS, ["ros_face"], 60.0)
            lat: dict[str, list[float]] = {t: [] for t in WATCHED}

            def on(topic, typename):
                def cb(sample):
                    msg = rc.deserialize(sample.payload.to_bytes(), typename)
                    header = msg.markers[0].header if topic == "markers" else msg.header
                    lat[topic].append((time.time_ns() - rc.stamp_of(header)) / 1e6)
                return cb
            subs = [session.declare_subscriber(rz.topic_key(DOMAIN, t, ty), on(t, ty))
                    for t, ty in WATCHED.items()]
            pubs = {}
            time.sleep(0.5)
            cpu0, wall0 = cpu_s(face.proc.pid), time.monotonic()
            for k in range(int(duration_s * 50)):
                time.sleep(max(0.0, wall0 + k * TICK_NS / 1e9 - time.monotonic()))
                for topic, msg in traffic(k, time.time_ns()):
                    pub = pubs.get(topic) or pubs.setdefault(
                        topic, session.declare_publisher(KEYS.key(topic)))
                    pub.put(msg.to_bytes())
            time.sleep(0.5)
            cpu1, wall1 = cpu_s(face.proc.pid), time.monotonic()
            for s in subs:
                s.undeclare()
    cycles = duration_s * CYCLE_HZ
    return {"duration_s": duration_s, "face_cpu_share": round((cpu1 - cpu0) / (wall1 - wall0), 4),
            "face_cpu_ms_per_cycle": round((cpu1 - cpu0) / cycles * 1e3, 3),
            "latency_to_face_key": {t: percentiles(v) for t, v in lat.items()}}


def run_once(world: str, planner: str, face: bool) -> dict:
    argv = [sys.executable, "-m", "papf", "run", "--world", world, "--planner", planner, "--json",
            "--port", str(free_port())]
    if face:
        argv += ["--ros-face", "--ros-face-domain", str(DOMAIN)]
    out = subprocess.run(argv, capture_output=True, text=True, timeout=900).stdout
    return json.loads(out)


def bench_runs(world: str, planner: str, runs: int) -> dict:
    results: dict[str, list[dict]] = {"plain": [], "face": []}
    for _ in range(runs):        # interleaved, so a load change hits both cases alike
        for name in results:
            results[name].append(run_once(world, planner, name == "face"))
    wall = {k: statistics.median(r["wall_time_s"] for r in v) for k, v in results.items()}
    sim = statistics.median(r["sim_time_s"] for r in results["plain"])
    cycles = sim * CYCLE_HZ
    same = all(r["outcome"] == results["plain"][0]["outcome"] and
               r["path_length_m"] == results["plain"][0]["path_length_m"]
               for r in results["plain"] + results["face"])
    return {"world": world, "planner": planner, "runs": runs,
            "wall_s": {k: [round(r["wall_time_s"], 2) for r in v] for k, v in results.items()},
            "median_wall_s": {k: round(v, 2) for k, v in wall.items()},
            "cycles": round(cycles), "same_figures": same,
            "face_wall_ms_per_cycle": round((wall["face"] - wall["plain"]) / cycles * 1e3, 3)}


CSV_FIELDS = ("metric", "value", "unit")


def rows(out: dict) -> list[tuple[str, float, str]]:
    n = out["node"]
    r = [("face_cpu_share", n["face_cpu_share"], "cores"),
         ("face_cpu_per_cycle", n["face_cpu_ms_per_cycle"], "ms")]
    for t, p in n["latency_to_face_key"].items():
        r += [(f"latency_{t}_p50", p.get("p50_ms", float("nan")), "ms"),
              (f"latency_{t}_p99", p.get("p99_ms", float("nan")), "ms")]
    if "run" in out:
        run = out["run"]
        r += [("run_wall_plain_median", run["median_wall_s"]["plain"], "s"),
              ("run_wall_face_median", run["median_wall_s"]["face"], "s"),
              ("run_face_wall_per_cycle", run["face_wall_ms_per_cycle"], "ms"),
              ("run_same_figures", int(run["same_figures"]), "bool")]
    return r


def main(argv=None) -> int:
    ap = ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=10.0, help="node benchmark length [s]")
    ap.add_argument("--runs", type=int, default=3, help="lockstep runs per case (0: skip)")
    ap.add_argument("--world", default="papf-test-4")
    ap.add_argument("--planner", default=one_with_role("papf-proposed"))
    ap.add_argument("--csv", metavar="F", help="also write the figures as CSV rows here")
    args = ap.parse_args(argv)
    if args.csv:   # this benchmark's table or a new file, known before the benchmark runs
        check_csv(Path(args.csv), CSV_FIELDS)
    out = {"node": bench_node(args.duration)}
    if args.runs:
        out["run"] = bench_runs(args.world, args.planner, args.runs)
    print(json.dumps(out, indent=2))
    if args.csv:   # the one output rule for a benchmark's CSV (bench/csvrows.py)
        write_rows(Path(args.csv), CSV_FIELDS, [dict(zip(CSV_FIELDS, r, strict=True))
                                               for r in rows(out)])
    return 0


if __name__ == "__main__":
    sys.exit(main())
