"""Per-planner statistics, the PAPF-vs-APF comparison with the paper, Markdown and CSV.

Statistics are per world and planner — runs of different worlds are never averaged
together — over the runs that **reached** the goal (the paper compares completed
runs; a collision or a timeout has no comparable charge): mean and sample standard
deviation (ddof = 1; nan for a single run). Changes are ``(other − base) / base`` of the
means, in %, base = APF.

Paper figures (Szczepanski et al. 2022, IEEE Access, PAPF): charge from section IV-C
(3 runs each, sum of the charger's readings): APF 149.7 mAh, PAPF 117.6 mAh, −32.1 mAh
= −21.4 %. Duration and path length from Table 2 (Tests I, II, III, VI: the ones both
planners completed): the printed reductions 40.23 / 20.63 / 10.45 / 14.69 % (duration;
the text: "around 21.5 % shorter") and 8.29 / 1.00 / 4.78 / 7.16 % (path).
"""

from __future__ import annotations

import csv
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from nodes.planner.registry import one_with_role
from papf.report.metrics import RunMetrics, seed_text

# (attribute, label, unit, format) of the figures that get statistics
STAT_METRICS: tuple[tuple[str, str, str, str], ...] = (
    ("charge_mAh", "charge", "mAh", ".2f"),
    ("energy_J", "energy", "J", ".1f"),
    ("mean_power_W", "mean power", "W", ".3f"),
    ("duration_s", "duration", "s", ".2f"),
    ("path_length_m", "path length", "m", ".3f"),
    ("ang_accel_sq", "∫β² dt", "rad²/s³", ".3g"),
    ("jerk_sq", "∫j² dt", "m²/s⁵", ".3g"),
    ("heading_oscillations", "heading oscillations", "", ".1f"),
)
TABLE2_DURATION_PCT = (-40.23, -20.63, -10.45, -14.69)   # PAPF paper Table 2, Tests I-III, VI
TABLE2_PATH_PCT = (-8.29, -1.00, -4.78, -7.16)
PAPER = {  # attribute -> what the paper reports for PAPF vs APF
    "charge_mAh": "149.7 → 117.6 mAh: −21.4 % (IV-C)",
    "duration_s": f"{np.mean(TABLE2_DURATION_PCT):+.1f} % (Table 2 mean; −10.45 … −40.23 %)",
    "path_length_m": f"{np.mean(TABLE2_PATH_PCT):+.1f} % (Table 2 mean; −1.00 … −8.29 %)",
    "ang_accel_sq": "“much smoother” (Fig. 13, not quantified)",
    "heading_oscillations": "APF oscillates, PAPF not (Fig. 13, not quantified)",
}
#: the PAPF paper's comparison (IV-C): its baseline (classic APF) and PAPF, by their declared roles
BASELINE, PROPOSED = one_with_role("papf-baseline"), one_with_role("papf-proposed")
PAPER_CHARGE_MAH = {BASELINE: 149.7, PROPOSED: 117.6}
PAPER_CHARGE_CHANGE_PCT = -21.4


@dataclass(frozen=True)
class Stat:
    mean: float
    sd: float
    n: int

    def text(self, fmt: str) -> str:
        if self.n == 0 or math.isnan(self.mean):
            return "–"
        return f"{self.mean:{fmt}} ± {self.sd:{fmt}}" if self.n > 1 else f"{self.mean:{fmt}}"


@dataclass(frozen=True)
class PlannerSummary:
    world: str
    planner: str
    runs: int
    reached: int
    stats: dict[str, Stat]


def planner_order(planners: Sequence[str]) -> list[str]:
    """The paper's baseline first, PAPF second, the rest alphabetically (the base of comparisons first)."""
    rank = {BASELINE: 0, PROPOSED: 1}
    return sorted(set(planners), key=lambda p: (rank.get(p.split(" ")[0], 2), p))


def worlds_of(runs: Sequence[RunMetrics]) -> list[str]:
    """The worlds of the runs, sorted (the report's sections, in this order)."""
    return sorted({r.world for r in runs})


def summarise(runs: Sequence[RunMetrics]) -> list[PlannerSummary]:
    """One summary per (world, planner): worlds sorted, planners in :func:`planner_order`."""
    out = []
    for world in worlds_of(runs):
        here = [r for r in runs if r.world == world]
        for planner in planner_order([r.planner for r in here]):
            mine = [r for r in here if r.planner == planner]
            done = [r for r in mine if r.outcome == "reached"]
            stats = {}
            for attr, *_ in STAT_METRICS:
                vals = np.array([float(getattr(r, attr)) for r in done])
                vals = vals[np.isfinite(vals)]
                stats[attr] = Stat(float(vals.mean()) if vals.size else math.nan,
                                   float(vals.std(ddof=1)) if vals.size > 1 else math.nan,
                                   int(vals.size))
            out.append(PlannerSummary(world, planner, len(mine), len(done), stats))
    return out


def change_pct(base: Stat, other: Stat) -> float:
    """(other − base) / base of the means [%]; nan when either is missing or base is 0."""
    if base.n == 0 or other.n == 0 or base.mean == 0:
        return math.nan
    return 100.0 * (other.mean - base.mean) / base.mean


# -- Markdown ---------------------------------------------------------------------------------
def _md_table(header: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(lines)


def _f(x: float, fmt: str) -> str:
    return "–" if x is None or (isinstance(x, float) and math.isnan(x)) else f"{x:{fmt}}"


def _unit(unit: str, model: str, attr: str) -> str:
    """Units of a figure; the energy model is named beside the ones it produced."""
    return f"{unit}, {model} model" if model and attr in MODEL_METRICS else unit


MODEL_METRICS = ("charge_mAh", "energy_J", "mean_power_W")


def runs_markdown(runs: Sequence[RunMetrics], model: str = "") -> str:
    m = f", {model} model" if model else ""
    header = ["run", "planner", "seed", "outcome", "duration [s]", "path [m]", f"charge [mAh{m}]",
              f"energy [J{m}]", f"mean P [W{m}]", "∫β² dt", "∫j² dt", "osc.",
              "live charge [mAh]", "re-meter Δ [mAh]"]
    rows = [[r.file, r.planner, seed_text(r.seed), r.outcome, _f(r.duration_s, ".2f"), _f(r.path_length_m, ".3f"),
             _f(r.charge_mAh, ".3f"), _f(r.energy_J, ".1f"), _f(r.mean_power_W, ".3f"),
             _f(r.ang_accel_sq, ".3g"), _f(r.jerk_sq, ".3g"), str(r.heading_oscillations),
             f"{_f(r.live_charge_mAh, '.3f')} @ {_f(r.live_stamp_s, '.2f')} s",
             _f(r.remeter_diff_mAh, ".3g")] for r in runs]
    return _md_table(header, rows)


def bags_markdown(runs: Sequence[RunMetrics], model: str = "") -> str:
    """Rosbag2s from the robot: path, duration, re-metered and measured charge side by side."""
    m = f", {model} model" if model else ""
    header = ["bag", "duration [s]", "path [m]", f"charge re-metered [mAh{m}]",
              "charge measured [mAh]", "measured / re-metered"]
    rows = [[r.file, _f(r.duration_s, ".2f"), _f(r.path_length_m, ".3f"), _f(r.charge_mAh, ".3f"),
             "none (/battery carries no current)" if r.measured_charge_mAh is None
             else _f(r.measured_charge_mAh, ".3f"),
             "–" if r.measured_charge_mAh is None or not r.charge_mAh
             else _f(r.measured_charge_mAh / r.charge_mAh, ".3f")] for r in runs]
    return _md_table(header, rows)


def summary_markdown(summaries: Sequence[PlannerSummary], model: str = "") -> str:
    """Mean ± sd per planner; give the summaries of one world (several: a world column)."""
    several = len({s.world for s in summaries}) > 1
    header = (["world"] if several else []) + ["planner", "reached"] + [
        f"{label} [{_unit(unit, model, a)}]" if unit else label
        for a, label, unit, _f2 in STAT_METRICS]
    rows = [([s.world] if several else []) + [s.planner, f"{s.reached}/{s.runs}"]
            + [s.stats[a].text(fmt) for a, _l, _u, fmt in STAT_METRICS] for s in summaries]
    return _md_table(header, rows)


def comparison_markdown(summaries: Sequence[PlannerSummary], model: str = "") -> str:
    """Every other planner against the first (APF) of one world, next to the paper's figures."""
    if len(summaries) < 2:
        return "_Only one planner: nothing to compare._"
    base = summaries[0]
    blocks = []
    for other in summaries[1:]:
        header = ["figure", f"{base.planner} (mean)", f"{other.planner} (mean)", "change",
                  "paper (PAPF vs APF)" if (base.planner, other.planner) == (BASELINE, PROPOSED)
                  else "paper"]
        paper_ok = (base.planner, other.planner) == (BASELINE, PROPOSED)
        rows = []
        for attr, label, unit, fmt in STAT_METRICS:
            b, o = base.stats[attr], other.stats[attr]
            rows.append([f"{label} [{_unit(unit, model, attr)}]" if unit else label,
                         _f(b.mean, fmt), _f(o.mean, fmt),
                         _f(change_pct(b, o), "+.1f") + (" %" if b.n and o.n else ""),
                         PAPER.get(attr, "") if paper_ok else ""])
        blocks.append(_md_table(header, rows))
    return "\n\n".join(blocks)


# -- CSV -------------------------------------------------------------------------------------
def write_csv(path: Path, runs: Sequence[RunMetrics], summaries: Sequence[PlannerSummary]) -> None:
    """One row per run (``row = run``), then per planner ``mean`` and ``sd`` rows."""
    fields = list(runs[0].row()) if runs else []
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=["row", "n", *fields], lineterminator="\n")
        w.writeheader()
        for r in runs:
            w.writerow({"row": "run", "n": 1, **{k: _csv(v) for k, v in r.row().items()}})
        for s in summaries:
            for kind in ("mean", "sd"):
                row = {"row": kind, "world": s.world, "planner": s.planner, "n": s.reached}
                row.update({a: _csv(getattr(s.stats[a], kind)) for a, *_ in STAT_METRICS})
                w.writerow(row)


def _csv(v: object) -> object:
    return repr(v) if isinstance(v, float) else v  # full precision, round-trips exactly
