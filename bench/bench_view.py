"""The Foxglove view's cost: the viewer node's CPU share and added latency, and a lockstep
``papf run`` with ``--view`` against one without.

    papf bench view [--duration 10] [--runs 3] [--world papf-test-4] [--planner papf]

1. **Node**: router and ``python -m nodes.viewer`` as processes; this process publishes the
   stack's traffic at its real rates — scan 10 Hz (300 beams), odom + sim/pose + battery
   50 Hz, cmd_vel + planner/state (a 40-point prediction, 3 abandoned ones, 3 quarks) +
   planner/status 10 Hz — stamped with the wall clock, for ``--duration`` s, while a
   Foxglove protocol client (``bench.foxglove_ws``) subscribes to every channel. Reports
   the viewer's CPU share of one core (``/proc`` utime + stime), and per channel the
   latency publish -> client receive (p50/p99), next to a plain Zenoh subscriber's in this
   process (the latency without the viewer): the difference is what the viewer adds.
2. **Run**: ``papf run --json`` in lockstep, ``--runs`` times each without ``--view``, with
   ``--view`` and no client, with ``--view`` and a client subscribed to everything;
   the wall time (median) of each and the slowdown against the plain run.

Prints one JSON object. Not a test: numbers depend on the machine and its load.
"""

from __future__ import annotations

import json
import math
import os
import statistics
import subprocess
import sys
import threading
import time

import numpy as np
import zenoh

from bench.foxglove_ws import FoxgloveClient
from common.cliparse import ArgumentParser
from common.transport import wait_alive, zenoh_config
from nodes.planner.debug import debug_values
from nodes.planner.registry import PLANNERS, one_with_role
from nodes.viewer.core import CHANNELS
from papf.launch.supervisor import Supervisor, free_port, wait_port
from schemas import Keys
from schemas.messages import BatteryState, Odometry, PlannerState, PlannerStatus, Scan, Twist

KEYS = Keys("rosbot")
TICK_NS = 20_000_000   # [ns] 50 Hz


def cpu_s(pid: int) -> float:
    """utime + stime of a process [s]."""
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


PROPOSED = PLANNERS[one_with_role("papf-proposed")]   # PAPF: the busiest mind to draw


def traffic(k: int, t_ns: int) -> list[tuple[str, object]]:
    """The stack's messages of one 20 ms tick ``k`` stamped ``t_ns``."""
    x = 0.001 * k
    pose = Odometry(stamp_ns=t_ns, x=x, y=0.0, yaw=0.1, v=0.1, w=0.0)
    out = [("sim/pose", pose), ("odom", pose), ("battery", BatteryState(
        stamp_ns=t_ns, voltage=12.0, current=1.0, power=12.0, charge_used_mAh=k * 1e-3,
        energy_J=k * 0.01))]
    if k % 5 == 0:
        ranges = (1.0 + np.random.default_rng(k).random(300)).astype(np.float32)
        ranges[::7] = np.inf
        line = tuple((x + 0.05 * i, 0.01 * i) for i in range(40))
        out += [("scan", Scan(stamp_ns=t_ns, angle_min=-math.pi, angle_increment=2 * math.pi / 300,
                              range_min=0.2, range_max=25.0, ranges=ranges)),
                ("cmd_vel", Twist(stamp_ns=t_ns, v=0.1, w=0.0)),
                ("planner/state", PlannerState(
                    stamp_ns=t_ns, algorithm=PROPOSED.name, mode="drive", force=(1.0, 0.2),
                    temporary_goal=(x + 2, 0.4), predicted_path=line,
                    debug=sample_debug(PROPOSED, line))),
                ("planner/status", PlannerStatus(stamp_ns=t_ns, state="driving",
                                                 distance_to_goal=3.0))]
    return out


def sample_debug(cls, line: tuple) -> tuple:
    """A busy cycle's debug values of planner ``cls``, one of each field it declares, by kind:
    three points, three paths cut from ``line``, a point, a scalar, a count."""
    by_kind = {"points": ((1.0, 1.0), (1.5, 0.5), (2.0, -0.5)),
               "paths": (line[:30], line[:20], line[:10]), "point": (1.0, 1.0),
               "scalar": 0.5, "count": 2}
    return debug_values(cls.name, cls.DEBUG, {f.name: by_kind[f.kind] for f in cls.DEBUG})


def percentiles(ms: list[float]) -> dict:
    if not ms:
        return {"n": 0}
    a = np.asarray(ms)
    return {"n": int(a.size), "p50_ms": round(float(np.percentile(a, 50)), 3),
            "p99_ms": round(float(np.percentile(a, 99)), 3)}


def bench_node(duration_s: float) -> dict:
    port, ws_port = free_port(), free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    with Supervisor(show=lambda n, line: "ERROR" in line) as sup:
        sup.start("router", [sys.executable, "-m", "papf.launch.router", "--listen", endpoint])
        assert wait_port(port, 15.0)
        viewer = sup.start("viewer", [sys.executable, "-m", "nodes.viewer", "--connect", endpoint,
                                      "--port", str(ws_port), "--world", "papf-test-4"])
        with zenoh.open(zenoh_config("client", [endpoint])) as session:
            assert not wait_alive(session, KEYS, ["viewer"], 30.0)
            client = FoxgloveClient(f"ws://127.0.0.1:{ws_port}")
            client.wait_for(lambda: len(client.topics()) >= len(CHANNELS))
            client.subscribe({c.topic for c in CHANNELS})
            direct: list[float] = []
            sub = session.declare_subscriber(KEYS.scan, lambda s: direct.append(
                time.time() - Scan.from_bytes(s.payload.to_bytes()).stamp_ns / 1e9))
            pubs = {}
            stop = threading.Event()

            def pump() -> None:
                while not stop.is_set():
                    client.pump(0.1)
            pumping = threading.Thread(target=pump, daemon=True)
            pumping.start()
            cpu0, wall0 = cpu_s(viewer.proc.pid), time.monotonic()
            for k in range(int(duration_s * 50)):
                due = wall0 + k * TICK_NS / 1e9
                time.sleep(max(0.0, due - time.monotonic()))
                for topic, msg in traffic(k, time.time_ns()):
                    pub = pubs.get(topic) or pubs.setdefault(
                        topic, session.declare_publisher(KEYS.key(topic)))
                    pub.put(msg.to_bytes())
            time.sleep(0.5)
            cpu1, wall1 = cpu_s(viewer.proc.pid), time.monotonic()
            stop.set()
            pumping.join()
            sub.undeclare()
            client.close()
    latency = {topic: percentiles([(recv - log_ns / 1e9) * 1e3 for log_ns, _, recv in msgs])
               for topic, msgs in sorted(client.messages.items()) if topic not in ("/world", "/goal")}
    return {"duration_s": duration_s, "viewer_cpu_share": round((cpu1 - cpu0) / (wall1 - wall0), 4),
            "latency_via_viewer": latency,
            "latency_zenoh_direct_scan": percentiles([d * 1e3 for d in direct])}


def run_once(world: str, planner: str, view: bool, client: bool) -> float:
    argv = [sys.executable, "-m", "papf", "run", "--world", world, "--planner", planner, "--json",
            "--port", str(free_port())]
    ws_port = free_port()
    if view:
        argv += ["--view", str(ws_port)]
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    watcher = None
    if client:
        def watch() -> None:
            try:
                c = FoxgloveClient(f"ws://127.0.0.1:{ws_port}", timeout_s=60.0)
            except OSError:
                return
            c.wait_for(lambda: len(c.topics()) >= len(CHANNELS) - 1, 30.0)
            c.subscribe({ch.topic for ch in CHANNELS})
            while proc.poll() is None:
                try:
                    c.pump(0.2)
                except Exception:   # the server went away with the run
                    return
        watcher = threading.Thread(target=watch, daemon=True)
        watcher.start()
    out, _ = proc.communicate(timeout=600)
    if watcher:
        watcher.join(5.0)
    result = json.loads(out)
    return float(result["wall_time_s"])


def bench_runs(world: str, planner: str, runs: int) -> dict:
    cases = {"plain": (False, False), "view": (True, False), "view+client": (True, True)}
    times: dict[str, list[float]] = {k: [] for k in cases}
    for _ in range(runs):        # interleaved, so a load change hits every case alike
        for name, (view, client) in cases.items():
            times[name].append(run_once(world, planner, view, client))
    med = {k: statistics.median(v) for k, v in times.items()}
    return {"world": world, "planner": planner, "runs": runs,
            "wall_s": {k: [round(x, 2) for x in v] for k, v in times.items()},
            "median_wall_s": {k: round(v, 2) for k, v in med.items()},
            "slowdown_pct": {k: round(100 * (med[k] / med["plain"] - 1), 1)
                             for k in ("view", "view+client")}}


def main(argv=None) -> int:
    ap = ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=10.0, help="node benchmark length [s]")
    ap.add_argument("--runs", type=int, default=3, help="lockstep runs per case (0: skip)")
    ap.add_argument("--world", default="papf-test-4")
    ap.add_argument("--planner", default=one_with_role("papf-proposed"))
    args = ap.parse_args(argv)
    out = {"node": bench_node(args.duration)}
    if args.runs:
        out["run"] = bench_runs(args.world, args.planner, args.runs)
    print(json.dumps(out, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
