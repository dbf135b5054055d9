"""``papf experiment iapf``: the IAPF paper's cases A-D at car scale (Jin 2024, Sec. 4, Table 2).

Each case world runs for the paper's case time with IAPF, IAPF without prediction and the
traditional APF in the paper's vehicle model (:mod:`papf.offline.road`); writes
``OUT/iapf.md`` and ``.csv``, time series and plots. Details: :func:`run_iapf_experiment`.
"""

from __future__ import annotations

import copy
import csv
import math
import time
from pathlib import Path

import numpy as np

from common.outfiles import output, replace_text
from nodes.planner.iapf.algorithm import HostState, IAPFCore
from nodes.planner.registry import car_variants
from nodes.planner.road import Track
from papf.offline.road import CAR_PLANNERS, car_params, lanes_of, mover
from papf.offline.run import simulate
from worlds import load_world

CASES = {"iapf-case-a": 5.0, "iapf-case-b": 5.0, "iapf-case-c": 6.0, "iapf-case-d": 10.0}
# the IAPF paper's Table 2 rows, as the iapf plug-in declares them (Strategy.car_variants)
IAPF, IAPF_NP, TRADITIONAL = PLANNERS = tuple(car_variants())
PLAN_EVERY_S = 0.1      # Table 2: planning frequency 0.1 s
# Table 2: case calculation time [s], single planning min-max [ms]
PAPER_TABLE2 = {("iapf-case-a", IAPF): (0.233, 4.130, 4.809),
                ("iapf-case-a", IAPF_NP): (0.181, 3.589, 3.771),
                ("iapf-case-a", TRADITIONAL): (0.167, 3.312, 3.397),
                ("iapf-case-b", IAPF): (0.225, 4.072, 4.629),
                ("iapf-case-c", IAPF): (0.233, 3.666, 4.129),
                ("iapf-case-d", IAPF): (0.476, 4.541, 4.969)}
# what Sec. 4.2 reports each planner doing
PAPER_SAYS = {("iapf-case-a", IAPF): "slows, then changes lanes",
              ("iapf-case-b", IAPF): "local minimum found, temporary goal, changes lanes",
              ("iapf-case-b", TRADITIONAL): "crashes (Fig. 11d-f)",
              ("iapf-case-c", IAPF): "follows, slows to 30.8 km/h",
              ("iapf-case-c", TRADITIONAL): "changes lanes (Fig. 12b-f)",
              ("iapf-case-d", IAPF): "changes lanes, slows for vehicle 4"}
COLUMNS = ["case", "planner", "case_time_s", "collisions", "min_clearance_m", "left_road",
           "lane_changes", "min_speed_kmh", "max_speed_kmh", "final_speed_kmh",
           "step_cpu_p50_ms", "step_cpu_p99_ms", "step_cpu_max_ms", "horizon_plans",
           "case_calc_s", "horizon_min_ms", "horizon_max_ms", "paper_case_calc_s",
           "paper_range_ms", "paper_says"]


def horizon_times(world, planner: str, run, params=(), horizon_s: float | None = None) -> list:
    """CPU time [ms] of planning a whole T = horizon_s trajectory from the run's state every
    :data:`PLAN_EVERY_S` (obstacles at constant velocity from their tracks at that time)."""
    p = car_params(planner, params)
    horizon_s = p.horizon_s if horizon_s is None else horizon_s
    lanes = lanes_of(world)
    y_goal = lanes.centre(lanes.lane_of(world.goal[1]))
    movers = [mover(ob, i) for i, ob in enumerate(world.obstacles)]
    every = max(1, int(round(PLAN_EVERY_S / p.step_s)))
    n = int(round(horizon_s / p.step_s))
    out = []
    core = IAPFCore(p)
    for k in range(0, run.states.shape[0] - 1, every):
        t = float(run.times[k])
        x, y, v, yaw = (float(c) for c in run.states[k])
        tracks = [m(t) for m in movers]
        plan_core = copy.copy(core)
        s = HostState(x, y, v, yaw)
        c0 = time.thread_time_ns()
        for j in range(n):
            moved = [Track(o.x + o.vx * j * p.step_s, o.y + o.vy * j * p.step_s, o.yaw, o.vx, o.vy,
                           o.length, o.width, o.id) for o in tracks]
            s, _ = plan_core.step(s, moved, lanes, t + j * p.step_s, y_goal)
        out.append((time.thread_time_ns() - c0) / 1e6)
    return out


def _row(case: str, planner: str, run, horizon: list) -> dict:
    v = run.states[:, 2] * 3.6
    cpu = run.step_cpu_us / 1e3
    paper = PAPER_TABLE2.get((case, planner))
    return {"case": case, "planner": planner, "case_time_s": CASES[case],
            "collisions": run.collisions, "min_clearance_m": round(run.min_clearance_m, 3),
            "left_road": run.left_road, "lane_changes": run.lane_changes,
            "min_speed_kmh": round(float(v.min()), 2), "max_speed_kmh": round(float(v.max()), 2),
            "final_speed_kmh": round(float(v[-1]), 2),
            "step_cpu_p50_ms": round(float(np.percentile(cpu, 50)), 4),
            "step_cpu_p99_ms": round(float(np.percentile(cpu, 99)), 4),
            "step_cpu_max_ms": round(float(cpu.max()), 4), "horizon_plans": len(horizon),
            "case_calc_s": round(sum(horizon) / 1e3, 4) if horizon else "",
            "horizon_min_ms": round(min(horizon), 3) if horizon else "",
            "horizon_max_ms": round(max(horizon), 3) if horizon else "",
            "paper_case_calc_s": paper[0] if paper else "",
            "paper_range_ms": f"{paper[1]:.3f}-{paper[2]:.3f}" if paper else "",
            "paper_says": PAPER_SAYS.get((case, planner), "")}


def write_series(out: Path, case: str, planner: str, run) -> None:
    """The host's time series of one run as CSV."""
    with output(out / f"{case}-{planner}.csv", force=True) as _tmp, open(_tmp, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["t", "x", "y", "v", "yaw", "temp_goal_y", "local_count"])
        for t, (x, y, v, yaw), tg, lc in zip(run.times, run.states, run.temp_goal,
                                             run.local_counts, strict=True):
            w.writerow([f"{t:.2f}", f"{x:.4f}", f"{y:.4f}", f"{v:.4f}", f"{yaw:.5f}",
                        "" if math.isnan(tg) else f"{tg:.2f}", int(lc)])


def write_vehicles(out: Path, case: str, world, duration: float, step_s: float) -> None:
    """The other vehicles' tracks at the planning step, as CSV (t, id, x, y, yaw, v, length, width)."""
    movers = [mover(ob, i) for i, ob in enumerate(world.obstacles)]
    with output(out / f"{case}-vehicles.csv", force=True) as _tmp, open(_tmp, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["t", "id", "x", "y", "yaw", "v", "length", "width"])
        for k in range(int(round(duration / step_s)) + 1):
            t = k * step_s
            for m in movers:
                o = m(t)
                w.writerow([f"{t:.2f}", o.id, f"{o.x:.4f}", f"{o.y:.4f}", f"{o.yaw:.5f}",
                            f"{o.speed:.4f}", o.length, o.width])


def markdown(rows: list[dict]) -> str:
    """The IAPF experiment's table (Markdown), our figures beside the paper's."""
    head = ["case", "planner", "case time [s]", "collisions", "min clearance [m]", "left road",
            "lane changes", "speed min-max [km/h]", "final [km/h]", "step CPU p50 / p99 [ms]",
            "case calc. [s]", "T = 5 s plan [ms]", "paper: case calc. [s]", "paper: plan [ms]",
            "paper: what it does"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        horizon = f"{r['horizon_min_ms']}-{r['horizon_max_ms']}" if r["horizon_plans"] else ""
        lines.append("| " + " | ".join(str(x) for x in [
            r["case"], CAR_PLANNERS[r["planner"]], r["case_time_s"], r["collisions"],
            r["min_clearance_m"], "yes" if r["left_road"] else "no", r["lane_changes"],
            f"{r['min_speed_kmh']}-{r['max_speed_kmh']}", r["final_speed_kmh"],
            f"{r['step_cpu_p50_ms']} / {r['step_cpu_p99_ms']}", r["case_calc_s"], horizon,
            r["paper_case_calc_s"], r["paper_range_ms"], r["paper_says"]]) + " |")
    return "\n".join(lines) + "\n"


def run_iapf_experiment(out: str | Path, planners=PLANNERS, cases=tuple(CASES), params=(),
                        horizon: bool = True, plots: bool = True, progress=None) -> list[dict]:
    """Run every case with every planner; write the table, CSVs and figures into ``out``.

    Each case world runs for the paper's case time (Table 2: 5, 5, 6, 10 s) with IAPF, IAPF
    without prediction and the traditional APF baseline, in the paper's vehicle model
    (:mod:`papf.offline.road`). Writes into ``OUT``:

    - ``iapf.md`` — a table like Table 2 (case time, computation) with what each planner did
      (collisions, clearance, off the road, lane changes, speeds) and the paper's figures;
    - ``iapf.csv`` — the same, one row per run; ``<case>-<planner>.csv`` the host's time series
      (t, x, y, v, yaw, temporary lane goal, eq. 24 count) and ``<case>-vehicles.csv`` the others';
    - ``<case>.png`` — trajectories with time marks and speed over time (like Figs. 10-13).

    Computation is thread CPU time (other processes on the machine disturb wall time): per
    planning step (0.02 s of driving), and, like Table 2, per "single planning" of a T = 5 s
    trajectory made every 0.1 s of the case.
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for case in cases:
        world = load_world(case)
        runs = {}
        for planner in planners:
            run = simulate(world, planner, params, max_time_s=CASES[case], whole_time=True).trace
            runs[planner] = run
            hz = horizon_times(world, planner, run, params) if horizon else []
            rows.append(_row(case, planner, run, hz))
            write_series(out, case, planner, run)
            if progress:
                progress(f"{case} {planner}: {run.collisions} collisions, "
                         f"{run.lane_changes} lane changes")
        write_vehicles(out, case, world, CASES[case], car_params(IAPF, params).step_s)
        if plots:
            from papf.plots.iapf_cases import plot_case  # matplotlib: only with plots

            plot_case(out / f"{case}.png", case, out, CAR_PLANNERS)
    with output(out / "iapf.csv", force=True) as _tmp, open(_tmp, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS)
        w.writeheader()
        w.writerows(rows)
    replace_text((out / "iapf.md"), markdown(rows))
    return rows
