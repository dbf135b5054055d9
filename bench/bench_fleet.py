"""Cost of a fleet against its size: ``papf run`` (the whole stack, lockstep) with R robots
and P people (generated worlds), as x real time and CPU per robot-cycle.

The robots drive parallel lanes 1.2 m apart towards goals 10 m ahead; the
people walk loops across the lanes (ORCA). Per (R, P) one run (``--continue-on-collision``)
is watched on its own bus from the bench: between the first robot's ``sim/pose`` at
``--short-s`` and at ``--long-s`` of sim time (start-up and shut-down left out):

- ``sim_over_wall`` = the sim time between the two samples / the wall time between them;
- ``cpu_ms_per_robot_cycle`` = the CPU of every process of the run (launcher and router,
  nodes; from /proc by ``bench.proc_cpu.TreeCPU``) between them / (R x the 100 ms cycles
  in it); ``driver_ms`` (the world simulator, ``nodes.world_sim``: physics, people, every robot's
  driver share),
  ``lidar_ms``, ``planner_ms``, ``meter_ms``, ``launcher_ms`` split it by kind of process
  (all robots' together; the launcher is also the run's router).

``--csv FILE --label L`` writes the rows labelled ``L`` (other labels kept). The machine's
2 cores may be shared (other work): the 1-minute load average of each row is written with it.

``--worlds W1,W2`` instead runs those worlds (robots that must pass each other: the packaged
``fleet-*``) to their outcome, once per ``--passing`` mode (``off``: each planner alone;
``orca``: the passing layer, nodes/planner/passing.py), and writes how many robots reached,
collided, the closest approach, the longest robot's duration, x real time over the whole
run (sim time over ``wall_time_s``) and the CPU split as above over the whole run.

    papf bench fleet [--robots 1,2,4,8] [--people 0,10,50] [--planner apf]
                     [--short-s 10] [--long-s 40] [--csv docs/data/fleet-scale.csv --label L]
    papf bench fleet --worlds fleet-ring-16,fleet-junction [--passing off,orca] [--planner papf]
                     [--timeout 120] [--csv docs/data/fleet-passing.csv --label L]
    papf bench fleet --driver-split 8,16 [--long-s 20] [--csv F --label L]

``--odom-hz HZ`` runs with ``papf run --odom-hz HZ`` (a fleet's odometry rate; by default the
scan rate, 10 Hz, in a fleet without people: docs/performance.md "A fleet's odometry rate").

``--driver-split R1,R2`` splits the world simulator's own CPU per robot-cycle (physics, tyre
forces, contacts, command gates, messages) in-process: :mod:`bench.fleet_driver`.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from common.cliparse import ArgumentParser

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import zenoh  # noqa: E402

from bench.csvrows import emit, replace_label  # noqa: E402
from bench.proc_cpu import TreeCPU  # noqa: E402
from common.errors import PapfError  # noqa: E402
from common.ports import plain  # noqa: E402
from common.transport import zenoh_config  # noqa: E402
from nodes.planner.registry import one_with_role  # noqa: E402
from papf.launch.profile import PASSING  # noqa: E402
from papf.launch.supervisor import free_port, wait_port  # noqa: E402
from schemas import Odometry  # noqa: E402
from worlds import load_world  # noqa: E402
from worlds.fleet import MAX_PEOPLE, MAX_ROBOTS  # noqa: E402

PARTS = {"nodes.world_sim": "driver", "nodes.lidar_sim": "lidar", "nodes.planner": "planner",
         "nodes.energy_meter": "meter", "papf": "launcher"}   # process (TreeCPU name) -> column
FIELDS = ("label", "robots", "people", "planner", "sim_s", "wall_s", "sim_over_wall",
          "cpu_ms_per_robot_cycle", *(f"{p}_ms" for p in PARTS.values()),
          "cpu_share_of_2_cores", "collisions", "load_avg_1min")
PASSING_FIELDS = ("label", "world", "robots", "planner", "passing", "reached", "collisions",
                  "min_separation_m", "duration_s", "sim_s", "wall_s", "sim_over_wall",
                  "cpu_ms_per_robot_cycle", *(f"{p}_ms" for p in PARTS.values()),
                  "load_avg_1min", "startup_s", "sim_over_wall_running")
CYCLE_S = 0.1     # [s] the lockstep cycle: one scan, one command per robot
LANE_M = 1.2      # [m] between the robots' lanes


def fleet_world(folder: Path, robots: int, people: int) -> Path:
    """R robots in lanes along +x, P people walking loops across the lanes ahead."""
    lines = [f'name = "bench-{robots}r-{people}p"\n']
    for i in range(robots):
        y = i * LANE_M
        lines.append(f'[[robots]]\nname = "r{i + 1}"\nstart = [0.0, {y:.2f}, 0.0]\n'
                     f'goal = [10.0, {y:.2f}]\n')
    span = max(robots - 1, 1) * LANE_M
    for k in range(people):
        x = 4.0 + (k * 16.0 / max(people, 1))          # spread over x 4..20 m
        y0, y1 = -2.0 - (k % 3) * 0.7, span + 2.0 + (k % 2) * 0.7
        a, b = ((x, y0), (x + 1.0, y1)) if k % 2 else ((x, y1), (x + 1.0, y0))
        lines.append(f'[[people]]\nstart = [{a[0]:.2f}, {a[1]:.2f}]\nwaypoints = [[{b[0]:.2f}, '
                     f'{b[1]:.2f}], [{a[0]:.2f}, {a[1]:.2f}]]\nloop = true\nspeed = 0.8\n')
    path = folder / f"fleet-{robots}r-{people}p.toml"
    path.write_text("".join(lines))
    return path


def stop(proc: subprocess.Popen) -> None:
    """End a ``papf run`` that is still going: SIGINT first, so the launcher stops its nodes
    (a SIGKILL would leave them running), then SIGKILL after 30 s."""
    if proc.poll() is not None:
        return
    proc.send_signal(signal.SIGINT)
    try:
        proc.wait(30)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()


def cpu_by_kind(tree: TreeCPU) -> dict[str, float]:
    """CPU seconds so far of the run's processes (the bench's own excluded): per
    :data:`PARTS` column, and ``total`` of them all (router and any other process too)."""
    while True:
        try:
            threads, names = dict(tree.threads), dict(tree.names)
            break
        except RuntimeError:   # the sampler added a thread meanwhile
            continue
    out = dict.fromkeys((*PARTS.values(), "total"), 0.0)
    for (pid, _), (_, cpu) in threads.items():
        if pid == tree.root:
            continue
        out["total"] += cpu
        col = PARTS.get(names.get(pid, ""))
        if col:
            out[col] += cpu
    return out


def measure(world: Path, robots: int, planner: str, short_s: float, long_s: float,
            passing: str | None = None, odom_hz: float | None = None) -> dict:
    """One ``papf run --json``, watched on its bus: the wall time and CPU between the first
    robot's pose samples at ``short_s`` and at ``long_s`` of sim time (module doc)."""
    port = free_port()
    marks: dict[str, tuple[float, dict]] = {}
    with TreeCPU() as tree:
        proc = subprocess.Popen([sys.executable, "-m", "papf", "run", "--world", str(world),
                                 "--planner", planner, "--timeout", f"{long_s + 0.5:g}",
                                 "--json", "--continue-on-collision", "--port", str(port),
                                 *(["--passing", passing] if passing else []), *odom_args(odom_hz)],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        try:
            if not wait_port(port, 60.0):
                raise SystemExit(f"papf run on {world.name}: no router on port {port}")

            def on_pose(sample) -> None:   # Zenoh's thread: note the wall time and CPU once
                t = Odometry.from_bytes(sample.payload.to_bytes()).stamp_ns / 1e9
                for mark, at in (("a", short_s), ("b", long_s)):
                    if t >= at and mark not in marks:
                        marks[mark] = (time.perf_counter(), cpu_by_kind(tree), t)

            with zenoh.open(zenoh_config("client", [f"tcp/127.0.0.1:{port}"])) as session:
                sub = session.declare_subscriber("r1/sim/pose", on_pose)
                out, err = proc.communicate(timeout=max(600.0, long_s * 20))
                sub.undeclare()
        finally:
            stop(proc)
    if set(marks) != {"a", "b"}:
        raise SystemExit(f"{world.name}: the run never reached {long_s:g} s of sim time: "
                         f"{(out.strip().splitlines() or [err.strip()[-300:]])[-1][:300]}")
    result = json.loads(out.strip().splitlines()[-1])
    (wall_a, cpu_a, sim_a), (wall_b, cpu_b, sim_b) = marks["a"], marks["b"]
    sim, wall = sim_b - sim_a, wall_b - wall_a
    cycles = robots * sim / CYCLE_S
    return {"sim_s": round(sim, 2), "wall_s": round(wall, 2),
            "sim_over_wall": round(sim / wall, 2),
            "cpu_ms_per_robot_cycle": round((cpu_b["total"] - cpu_a["total"]) / cycles * 1e3, 2),
            **{f"{col}_ms": round((cpu_b[col] - cpu_a[col]) / cycles * 1e3, 2)
               for col in PARTS.values()},
            "cpu_share_of_2_cores": round((cpu_b["total"] - cpu_a["total"]) / wall / 2, 2),
            "collisions": result["collisions"], "load_avg_1min": round(os.getloadavg()[0], 1)}


def odom_args(odom_hz: float | None) -> list[str]:
    """``papf run --odom-hz`` when given (else the run's default: 50, a fleet's the scan rate)."""
    return [] if odom_hz is None else ["--odom-hz", f"{odom_hz:g}"]


def outcome_row(world: str, planner: str, passing: str, timeout_s: float,
                odom_hz: float | None = None) -> dict:
    """One fleet world to its outcome with the passing layer ``passing``: the row.

    Besides ``sim_over_wall`` over the whole run (start-up included), the run is watched on
    its bus: ``startup_s`` = wall time from the launch to the first robot's first pose,
    ``sim_over_wall_running`` = sim time over wall time between that robot's first and last
    pose (the real-time factor while the world runs, as simulators quote it)."""
    fleet = load_world(world).robots
    robots, first = len(fleet), fleet[0].name
    load = os.getloadavg()[0]
    port, poses = free_port(), []   # (wall [s], sim [s]) of the first and the latest pose

    def on_pose(sample) -> None:   # Zenoh's thread
        mark = (time.perf_counter(), Odometry.from_bytes(sample.payload.to_bytes()).stamp_ns / 1e9)
        if poses:
            poses[1:] = [mark]
        else:
            poses.append(mark)

    with TreeCPU() as tree:
        launched = time.perf_counter()
        proc = subprocess.Popen([sys.executable, "-m", "papf", "run", "--world", world,
                                 "--planner", planner, "--timeout", f"{timeout_s:g}", "--json",
                                 "--passing", passing, "--port", str(port), *odom_args(odom_hz)],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        try:
            if not wait_port(port, 60.0):
                raise SystemExit(f"papf run on {world}: no router on port {port}")
            with zenoh.open(zenoh_config("client", [f"tcp/127.0.0.1:{port}"])) as session:
                sub = session.declare_subscriber(f"{first}/sim/pose", on_pose)
                out, err = proc.communicate(timeout=max(900.0, timeout_s * 30))
                sub.undeclare()
        finally:
            stop(proc)
        cpu = cpu_by_kind(tree)
    lines = [ln for ln in out.splitlines() if ln.startswith("{")]
    if not lines:
        raise SystemExit(f"bench fleet: {world} --passing {passing}: no JSON (exit "
                         f"{proc.returncode}): {err.strip().splitlines()[-1:]}")
    r = json.loads(lines[-1])
    sim, wall = r["sim_time_s"], r["wall_time_s"]
    cycles = robots * sim / CYCLE_S
    return {"world": world, "robots": robots, "planner": planner, "passing": passing,
            "reached": sum(x["outcome"] == "reached" for x in r["robots"]),
            "collisions": r["collisions"], "min_separation_m": r["min_separation_m"],
            "duration_s": r["duration_s"], "sim_s": sim, "wall_s": round(wall, 2),
            "sim_over_wall": round(sim / wall, 2) if wall > 0 else None,
            "cpu_ms_per_robot_cycle": round(cpu["total"] / cycles * 1e3, 2) if cycles else None,
            **{f"{col}_ms": round(cpu[col] / cycles * 1e3, 2) if cycles else None
               for col in PARTS.values()},
            "load_avg_1min": round(load, 1), **_running(launched, poses)}


def _running(launched: float, poses: list) -> dict:
    """``startup_s`` and ``sim_over_wall_running`` from the first robot's first and latest
    pose (``outcome_row``); empty when fewer than two came."""
    if len(poses) < 2 or poses[1][0] <= poses[0][0]:
        return {"startup_s": None, "sim_over_wall_running": None}
    (w0, s0), (w1, s1) = poses
    return {"startup_s": round(w0 - launched, 2),
            "sim_over_wall_running": round((s1 - s0) / (w1 - w0), 2)}


def main_worlds(args) -> None:
    """``--worlds``: each world once per ``--passing`` mode, to its outcome (module doc)."""
    rows = []
    for world in [w for w in args.worlds.split(",") if w]:
        for passing in [m for m in args.passing.split(",") if m]:
            row = outcome_row(world, args.planner or one_with_role("papf-proposed"), passing,
                              args.timeout, args.odom_hz)
            emit(rows, row, args.label)
    if args.csv:
        replace_label(args.csv, PASSING_FIELDS, args.label, rows)


def parse(argv=None) -> argparse.Namespace:
    """The options (module doc); a usage error exits 2 in one line."""
    parser = ArgumentParser(prog="papf bench fleet",
                                     description=plain(__doc__.splitlines()[0]))
    parser.add_argument("--robots", default="1,2,4,8", help="robot counts")
    parser.add_argument("--people", default="0,10,50", help="people counts")
    baseline = one_with_role("papf-baseline")
    parser.add_argument("--planner", help=f"every robot's planner ({baseline}; with --worlds "
                        f"{one_with_role('papf-proposed')})")
    parser.add_argument("--short-s", type=float, default=10.0, help="sim s of the short run")
    parser.add_argument("--long-s", type=float, default=40.0, help="sim s of the long run")
    parser.add_argument("--csv", type=Path, help="write the rows here (with --label)")
    parser.add_argument("--label", help="the rows' label in --csv")
    parser.add_argument("--worlds", help="fleet worlds to their outcome instead (module doc)")
    parser.add_argument("--passing", help="the passing layer: with --worlds the modes to compare "
                        "(default off,orca), else the one of every run (default the run's: orca "
                        "with two or more robots)")
    parser.add_argument("--odom-hz", type=float,
                        help="papf run --odom-hz (default: the run's, 50; a fleet's the scan rate)")
    parser.add_argument("--timeout", type=float, default=120.0,
                        help="with --worlds: sim seconds at most (120)")
    parser.add_argument("--driver-split", metavar="R1,R2",
                        help="robot counts: the world simulator's CPU split in-process instead")
    args = parser.parse_args(argv)
    if bool(args.csv) != bool(args.label):
        parser.error("--csv and --label go together")
    if args.worlds:
        args.passing = args.passing or ",".join(reversed(PASSING))
        bad = [m for m in args.passing.split(",") if m not in PASSING]
        if bad or not 0 < args.timeout <= 3600:
            parser.error(f"--passing takes {','.join(PASSING)}; --timeout in (0, 3600] s")
        try:
            for world in [w for w in args.worlds.split(",") if w]:
                load_world(world)   # a bad name: one line, before any run
        except PapfError as exc:
            parser.error(str(exc))
        return args
    args.planner = args.planner or baseline
    if args.passing not in (None, *PASSING):
        parser.error(f"--passing takes one of {', '.join(PASSING)}")
    try:
        args.robot_counts = [int(v) for v in (args.driver_split or args.robots).split(",") if v]
        args.people_counts = [int(v) for v in args.people.split(",") if v]
    except ValueError:
        parser.error("--robots and --people are comma-separated integers, e.g. 1,2,4,8")
    if not (all(1 <= r <= MAX_ROBOTS for r in args.robot_counts)
            and all(0 <= p <= MAX_PEOPLE for p in args.people_counts)):
        parser.error(f"robots in 1..{MAX_ROBOTS}, people in 0..{MAX_PEOPLE} (the world format's limits)")
    if not 0 < args.short_s < args.long_s:
        parser.error("need 0 < --short-s < --long-s")
    return args


def main_split(args) -> None:
    """``--driver-split``: the driver's CPU split per robot count (bench.fleet_driver)."""
    from bench.fleet_driver import SPLIT_FIELDS, split

    rows = []
    with tempfile.TemporaryDirectory(prefix="papf-bench-fleet-") as tmp:
        for robots in args.robot_counts:
            row = {**split(fleet_world(Path(tmp), robots, 0), args.long_s),
                   "load_avg_1min": round(os.getloadavg()[0], 1)}
            emit(rows, row, args.label)
    if args.csv:
        replace_label(args.csv, SPLIT_FIELDS, args.label, rows)


def main(argv=None) -> None:
    args = parse(argv)
    if args.worlds:
        main_worlds(args)
        return
    if args.driver_split:
        main_split(args)
        return
    rows = []
    with tempfile.TemporaryDirectory(prefix="papf-bench-fleet-") as tmp:
        for people in args.people_counts:
            for robots in args.robot_counts:
                world = fleet_world(Path(tmp), robots, people)
                row = {"robots": robots, "people": people, "planner": args.planner,
                       **measure(world, robots, args.planner, args.short_s, args.long_s,
                                 args.passing, args.odom_hz)}
                emit(rows, row, args.label)
    if args.csv:
        replace_label(args.csv, FIELDS, args.label, rows)

if __name__ == "__main__":
    main()
