"""Cost against the size of the world: worlds of N cylinders and square halls from ROS maps
of W x W m at 5 cm, each run by the world simulator + LiDAR loop (the ``papf bench sim
--loop`` chain: ``nodes.world_sim`` and ``nodes.lidar_sim`` as processes, every scan
answered here with a constant Twist).

Per world: ``start_s`` (processes started -> both alive: parsing, building the pybullet
scene), ``sim_over_wall`` (sim time / wall time over ``--sim-s``), ``cpu_ms_per_cycle``
(CPU of both nodes per 100 ms cycle, from /proc) and ``rss_mb`` (the two nodes' peak
resident memory, VmHWM). ``--csv FILE --label L`` writes the rows labelled ``L`` (other
labels kept: before/after). The other helpers' work shares this machine's 2 cores: the
load average of each row is written with it.

    papf bench world-scale [--obstacles 0,500,2000,10000] [--maps 10,100] [--sim-s 20]
                           [--csv docs/data/world-scale.csv --label after]
"""

from __future__ import annotations

import os
import sys
import tempfile
import threading
import time
from pathlib import Path

from common.cliparse import ArgumentParser

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402
import zenoh  # noqa: E402

from bench.csvrows import check_csv, emit, replace_label  # noqa: E402
from common.ports import plain  # noqa: E402
from common.transport import wait_alive, zenoh_config  # noqa: E402
from papf.launch.supervisor import Supervisor, free_port, wait_port  # noqa: E402
from papf.offline import map_gen  # noqa: E402
from schemas import Keys  # noqa: E402
from schemas.messages import Clock, Event, Scan, Twist  # noqa: E402
from worlds.maps import OccupancyMap, save_map  # noqa: E402

FIELDS = ("label", "world", "obstacles", "cells", "start_s", "sim_s", "wall_s", "sim_over_wall",
          "cpu_ms_per_cycle", "rss_mb", "load_avg_1min")
CYCLE_S = 0.1      # [s] the lockstep cycle (one scan, one command)
RES_M = 0.05       # [m/cell] of the map halls
CLEAR_M = 7.0      # [m] around the start, free of cylinders (the arc reaches 6 m + the robot)


def cylinders_world(folder: Path, n: int) -> Path:
    """``n`` cylinders (r 0.1 m) scattered over 100 x 100 m, none within :data:`CLEAR_M` of the
    start: the bench's arc (0.3 m/s, 0.1 rad/s: a 3 m circle through the start) never touches
    one, so each cycle pays for what the robot sees (a run ends at its first contact)."""
    xy = np.random.default_rng(11).uniform(-50, 50, (n * 2, 2))
    xy = xy[np.hypot(xy[:, 0], xy[:, 1]) > CLEAR_M][:n]
    lines = ['[robot]\nstart = [0.0, 0.0, 0.0]\n[goal]\nposition = [40.0, 0.0]\n']
    lines += [f'[[obstacles]]\nkind = "cylinder"\ncenter = [{x:.3f}, {y:.3f}]\nradius = 0.1\n'
              for x, y in xy]
    path = folder / f"cylinders-{n}.toml"
    path.write_text("".join(lines))
    return path


def hall_world(folder: Path, width_m: int) -> tuple[Path, int]:
    """A ``width_m`` square hall at :data:`RES_M` with pillars (map_gen.hall); its cells."""
    data = map_gen.hall(width_m, RES_M, pillars=width_m * 4)
    save_map(OccupancyMap(data, RES_M, (-width_m / 2 - 0.5, -width_m / 2 - 0.5, 0.0)),
             folder / f"hall-{width_m}.yaml")
    path = folder / f"hall-{width_m}.toml"
    path.write_text(f'[robot]\nstart = [0.0, 0.0, 0.0]\n[goal]\nposition = [5.0, 0.0]\n'
                    f'[map]\nfile = "hall-{width_m}.yaml"\n')
    return path, int(data.size)


def _proc(pid: int) -> tuple[float, float]:
    """(CPU seconds, peak RSS MB) of process ``pid`` from /proc."""
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    cpu = (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    with open(f"/proc/{pid}/status") as f:
        hwm = next(int(line.split()[1]) for line in f if line.startswith("VmHWM"))
    return cpu, hwm / 1024


def run(world: Path, sim_s: float) -> dict:
    """Start the driver and the LiDAR on ``world``, drive ``sim_s`` of sim time, measure."""
    keys, port = Keys("rosbot"), free_port()
    endpoint, py = f"tcp/127.0.0.1:{port}", sys.executable
    with Supervisor(show=lambda *_: False) as sup:
        sup.start("router", [py, "-m", "papf.launch.router", "--listen", endpoint])
        if not wait_port(port, 20):
            raise RuntimeError(f"router did not start on {endpoint}")
        t_start = time.perf_counter()
        nodes = [sup.start(n, [py, "-m", module, "--connect", endpoint, "--world", str(world)])
                 for n, module in (("base_driver", "nodes.world_sim"), ("lidar_sim", "nodes.lidar_sim"))]
        with zenoh.open(zenoh_config("client", [endpoint])) as session:
            missing = wait_alive(session, keys, ["base_driver", "lidar_sim"], 120,
                                 abort=lambda: bool(sup.dead()))
            if missing:
                raise RuntimeError(f"nodes not alive on {world.name}: {missing}")
            start_s = time.perf_counter() - t_start
            cpu0 = sum(_proc(c.proc.pid)[0] for c in nodes)
            wall = _drive(session, keys, sim_s)
            usage = [_proc(c.proc.pid) for c in nodes]
    return {"start_s": round(start_s, 2), "sim_s": sim_s, "wall_s": round(wall, 3),
            "sim_over_wall": round(sim_s / wall, 2),
            "cpu_ms_per_cycle": round((sum(u[0] for u in usage) - cpu0) / (sim_s / CYCLE_S) * 1e3, 2),
            "rss_mb": round(sum(u[1] for u in usage), 1),
            "load_avg_1min": round(os.getloadavg()[0], 1)}


def _drive(session, keys: Keys, sim_s: float) -> float:
    """Answer every scan with a slow arc until sim time ``sim_s`` [s]; the wall time [s]."""
    cmd = session.declare_publisher(keys.cmd_vel)
    done, lock = threading.Event(), threading.Lock()

    def on_scan(sample):
        scan = Scan.from_bytes(sample.payload.to_bytes())
        with lock:
            if not done.is_set():
                cmd.put(Twist(stamp_ns=scan.stamp_ns, v=0.3, w=0.1).to_bytes())

    def on_clock(sample):
        if Clock.from_bytes(sample.payload.to_bytes()).stamp_ns >= sim_s * 1e9:
            done.set()

    subs = [session.declare_subscriber(keys.scan, on_scan),
            session.declare_subscriber(keys.clock, on_clock)]
    t0 = time.perf_counter()
    session.put(keys.events, Event(stamp_ns=0, kind="run_started", source="bench").to_bytes())
    if not done.wait(timeout=max(120.0, sim_s * 10)):
        raise RuntimeError(f"{sim_s} s of sim time did not pass within {max(120.0, sim_s * 10)} s")
    wall = time.perf_counter() - t0
    with lock:
        done.set()
    for sub in subs:
        sub.undeclare()
    cmd.undeclare()
    return wall


def main() -> None:
    parser = ArgumentParser(prog="papf bench world-scale",
                                     description=plain(__doc__.splitlines()[0]))
    parser.add_argument("--obstacles", default="0,500,2000,10000", help="cylinder counts")
    parser.add_argument("--maps", default="10,100", help="hall widths [m] at 5 cm")
    parser.add_argument("--sim-s", type=float, default=20.0, help="sim seconds per world (20)")
    parser.add_argument("--csv", type=Path, help="write the rows here (with --label)")
    parser.add_argument("--label", help="the rows' label in --csv (e.g. after)")
    args = parser.parse_args()
    if args.csv:   # a foreign file: refused before the work, not after
        check_csv(args.csv, FIELDS)
    if bool(args.csv) != bool(args.label):
        parser.error("--csv and --label go together")
    counts = [int(v) for v in args.obstacles.split(",") if v]
    widths = [int(v) for v in args.maps.split(",") if v]
    rows = []
    with tempfile.TemporaryDirectory(prefix="papf-world-scale-") as tmp:
        folder = Path(tmp)
        cases = [(cylinders_world(folder, n), n, 0) for n in counts]
        cases += [(path, 0, cells) for path, cells in (hall_world(folder, w) for w in widths)]
        for world, n, cells in cases:
            row = {"world": world.stem, "obstacles": n, "cells": cells, **run(world, args.sim_s)}
            emit(rows, row, args.label)
    if args.csv:
        replace_label(args.csv, FIELDS, args.label, rows)


if __name__ == "__main__":
    main()
