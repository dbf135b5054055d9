"""``papf experiment energy --worlds energy,energy-blocking,energy-empty``: the energy
experiment on several worlds, and one table that separates the effects (issue 14).

``energy`` (the paper's course), ``energy-blocking`` (obstacles across the line) and
``energy-empty`` (the control, no obstacle), each as :func:`papf.experiments.energy.run_experiment`;
then ``OUT/energy-worlds.csv`` and ``.md``. Details: :func:`run_energy_worlds`.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from pathlib import Path

from common.outfiles import replace_text
from nodes.planner.registry import one_with_role

# the planners the papers' comparisons are about, by their declared roles (nodes/planner/registry.py)
APF = one_with_role("papf-baseline")

WORLDS = ("energy", "energy-blocking", "energy-empty")
HEADER = ["world", "planner", "reached", "charge [mAh]", "duration [s]", "path [m]",
          "charge vs APF", "max temporary-goal offset [m]", "quarks away from the goal"]


def _num(x: float, nd: int) -> str:
    return "" if not math.isfinite(x) else f"{x:.{nd}f}"


def world_rows(world: str, report) -> list[dict]:
    """CSV rows of one world's report (means over the runs that reached)."""
    from papf.report.activity import papf_activity

    apf = report.summary(APF)
    rows = []
    for s in report.summaries:
        files = [report.out_dir / m.file for m in report.runs if m.planner == s.planner]
        acts = [papf_activity(f) for f in files]
        charge = s.stats["charge_mAh"].mean
        base = apf.stats["charge_mAh"].mean if apf and apf.reached else math.nan
        change = 100.0 * (charge - base) / base if math.isfinite(base) and s.planner != APF else math.nan
        rows.append({"world": world, "planner": s.planner, "reached": f"{s.reached}/{s.runs}",
                     "charge_mAh": _num(charge, 2), "charge_sd_mAh": _num(s.stats["charge_mAh"].sd, 2),
                     "duration_s": _num(s.stats["duration_s"].mean, 2),
                     "duration_sd_s": _num(s.stats["duration_s"].sd, 2),
                     "path_m": _num(s.stats["path_length_m"].mean, 3),
                     "path_sd_m": _num(s.stats["path_length_m"].sd, 3),
                     "charge_vs_apf_pct": _num(change, 1),
                     "max_goal_offset_m": _num(max(a.max_goal_offset_m for a in acts), 2) if acts else "",
                     "quarks_away": max(a.quarks_away for a in acts) if acts else 0})
    return rows


def run_energy_worlds(exp, worlds: Sequence[str] = WORLDS, console=None) -> list:
    """Run ``exp`` on each world (into ``exp.out/world-<world>``); write the combined table.

    - ``energy`` — the paper's course (goal 10 m, three obstacles beside the line);
    - ``energy-blocking`` — the same course with the obstacles across the line, so PAPF's
      temporary goal and top quarks have to work;
    - ``energy-empty`` — the control: no obstacle; any saving there comes from the motion law
      alone (APF's 5 / r^2 pull is below V_max beyond 7.1 m, PAPF's temporary goal <= lambda
      away always pulls with >= 5).

    Each world runs as :func:`papf.experiments.energy.run_experiment` into ``OUT/world-<world>/``
    (recordings, report); then ``OUT/energy-worlds.csv`` and ``.md``: per world and planner
    (preset) the runs that reached, mean charge, duration and path, the charge change against
    APF in the same world, and what PAPF did (:mod:`papf.report.activity`).
    """
    from papf.experiments.energy import run_experiment

    out = Path(exp.out)
    results = []
    for world in worlds:
        res = run_experiment(dataclasses.replace(exp, out=out / f"world-{world}", world=world),
                             console)
        results.append(res)
    write_tables(out, [(w, r.report) for w, r in zip(worlds, results, strict=True)], exp.runs, exp.seed)
    return results


def write_tables(out: Path, reports, runs: int, seed: int) -> None:
    """``out/energy-worlds.csv`` and ``.md`` from (world, report) pairs."""
    from papf.experiments.trials import markdown_table, write_csv

    rows = [row for world, report in reports for row in world_rows(world, report)]
    write_csv(rows, out / "energy-worlds.csv")
    md = [[r["world"], r["planner"], r["reached"],
           f"{r['charge_mAh']} ± {r['charge_sd_mAh']}" if r["charge_sd_mAh"] else r["charge_mAh"],
           r["duration_s"], r["path_m"], f"{r['charge_vs_apf_pct']} %" if r["charge_vs_apf_pct"] else "",
           r["max_goal_offset_m"], r["quarks_away"]] for r in rows]
    split = decomposition(rows)
    text = (f"# Energy worlds ({runs} runs each, seeds {seed + 1}-{seed + runs})\n\n"
            + markdown_table(HEADER, md))
    if split:
        write_csv(split, out / "energy-decomposition.csv")
        text += "\n## Where the saving in `energy` comes from\n\n" + markdown_table(
            list(split[0]), [list(r.values()) for r in split])
    replace_text((out / "energy-worlds.md"), text)


def decomposition(rows: list[dict], course: str = "energy", control: str = "energy-empty") -> list[dict]:
    """Split each planner's saving against APF on ``course`` into the part it already makes on
    the empty ``control`` course (speed far from the goal: the motion law alone) and the rest
    (avoidance). Empty when a world or APF's figure is missing."""
    by = {(r["world"], r["planner"]): r for r in rows}
    try:
        apf_c, apf_e = float(by[(course, APF)]["charge_mAh"]), float(by[(control, APF)]["charge_mAh"])
    except (KeyError, ValueError):
        return []
    out = []
    for (world, planner), r in by.items():
        if world != course or planner == APF or (control, planner) not in by or not r["charge_mAh"]:
            continue
        total = apf_c - float(r["charge_mAh"])
        speed = apf_e - float(by[(control, planner)]["charge_mAh"])
        out.append({"planner": planner, "saving_mAh": round(total, 2), "from_speed_mAh": round(speed, 2),
                    "from_avoidance_mAh": round(total - speed, 2),
                    "speed_share_pct": round(100 * speed / total, 1) if total else "",
                    "avoidance_share_pct": round(100 * (total - speed) / total, 1) if total else ""})
    return out
