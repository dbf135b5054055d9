"""Two studies of PAPF against its paper (offline, :func:`papf.offline.run.simulate`):

- ``papf experiment horizon`` (:func:`run_horizon`): PAPF IV-A / Fig. 7, lambda swept;
- ``papf experiment deviations`` (:func:`run_deviations`): each of our deviations from the
  literal PAPF switched alone.

Both write ``OUT/<name>.csv`` and ``OUT/<name>.md``.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from common.outfiles import replace_text
from nodes.planner.registry import one_with_role

# the planners the papers' comparisons are about, by their declared roles (nodes/planner/registry.py)
APF = one_with_role("papf-baseline")
PAPF = one_with_role("papf-proposed")

HORIZONS = (0.5, 1.0, 1.5, 2.0)
HORIZON_WORLD = "papf-horizon"

#: (setting, default value, paper value, what it is)
DEVIATIONS = (
    ("pull_range_fraction", "1.0", "0.0", "prediction's goal pull evaluated at most lambda away"),
    ("motion_quarks_within_d_o", "true", "false", "motion law: quarks act within d_o, not d_q"),
    ("quark_ball_m", "0.25", "0.0", "motion law: a quark is a charged ball of radius lambda_stag"),
    ("unresolved_global_goal", "true", "false", "after M repetitions: eq. 7 with the global goal"),
    ("stop_at_goal", "true", "false", "the prediction stops at the goal"),
    ("quark_restarts_watch", "true", "false", "a placed quark restarts the stagnation watch"),
    ("replace_oldest_quark", "true", "false", "beyond M quarks the oldest gives way (paper: at most M per goal)"),
)

#: (setting, value, what it is): other readings of the paper's text, each tried on top of
#: ``--preset paper`` (the text allows them; the preset takes the other one, docs/planners.md)
READINGS = (
    ("persist_quarks", "false", "quarks recomputed every cycle (none kept from the last one)"),
    ("d_q", "0.5", "d_q = d_o = 0.5 m (eq. 7's where-clause names d_o)"),
)


def _turning(headings: np.ndarray) -> float:
    """Sum of |heading change| [rad] over the run."""
    if headings.size < 2:
        return 0.0
    return float(np.sum(np.abs(np.angle(np.exp(1j * np.diff(headings))))))


def run_horizon(out: str | Path, seed: int = 0, horizons: Sequence[float] = HORIZONS,
                world: str = HORIZON_WORLD) -> list[dict]:
    """PAPF with each horizon (both presets) and APF on ``world``; write horizon.csv/.md.

    PAPF IV-A / Fig. 7 — lambda in {0.5, 1, 1.5, 2} m on the Fig. 7-like world
    ``papf-horizon`` (goal 7 m straight ahead, three obstacles), both presets, APF for
    reference: outcome, duration, path length, turning (sum of |heading change|, the
    smoothness the paper judges by eye), and the planner's cycle time
    (``PlannerState.compute_ns``, median and 99th percentile).
    """
    from papf.console.progress import StepProgress
    from papf.experiments.trials import markdown_table, write_csv

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    runs = [(APF, "default", None)] + [(PAPF, pre, h) for pre in ("default", "paper")
                                         for h in horizons]
    rows = []
    with StepProgress("horizon", len(runs)) as progress:
        for planner, preset, h in runs:
            rows.append(_horizon_row(world, planner, preset, h, seed))
            progress.step(f"{planner} {preset} lambda {h or '-'} m: {rows[-1]['outcome']}")
    write_csv(rows, out / "horizon.csv")
    replace_text((out / "horizon.md"), f"# Horizon of prediction on {world} (offline, seed {seed})\n\n"
                                    + markdown_table(list(rows[0]), [list(r.values()) for r in rows]))
    return rows


def _horizon_row(world: str, planner: str, preset: str, h: float | None, seed: int) -> dict:
    """One run of the horizon study as its table row."""
    from papf.offline.run import simulate

    sets = (["preset=paper"] if preset == "paper" else []) + ([f"horizon_m={h}"] if h else [])
    r = simulate(world, planner, params=sets, seed=seed, keep_states=True)
    cyc = np.array([s.compute_ns for s in r.states], float) / 1e6
    return {"planner": planner, "preset": preset, "horizon_m": "" if h is None else h,
            "outcome": r.outcome, "duration_s": round(r.duration_s, 1),
            "path_m": round(r.length_m, 2), "turning_rad": round(_turning(r.headings), 2),
            "min_clearance_m": round(r.min_clearance_m, 2),
            "cycle_ms_p50": round(float(np.median(cyc)), 2) if cyc.size else "",
            "cycle_ms_p99": round(float(np.percentile(cyc, 99)), 2) if cyc.size else ""}


def _variants(both: bool = False) -> list[tuple[str, list[str]]]:
    """default, paper, the paper preset with each other reading of :data:`READINGS`, and
    each deviation switched on alone over the paper preset; with
    ``both`` also each deviation switched off alone from the default."""
    out = [("default", []), ("paper", ["preset=paper"])]
    out += [(f"paper with {name}={value}", ["preset=paper", f"{name}={value}"]) for name, value, _w in READINGS]
    for name, on, off, _what in DEVIATIONS:
        out.append((f"paper + {name}", ["preset=paper", f"{name}={on}"]))
        if both:
            out.append((f"default - {name}", [f"{name}={off}"]))
    return out


def _group(label: str) -> str:
    """The deviation study's row group: preset, reading, paper + deviation, default - deviation."""
    if label in ("default", "paper"):
        return "preset"
    if label.startswith("paper with "):
        return "reading"
    return "paper + deviation" if label.startswith("paper + ") else "default - deviation"


def run_deviations(out: str | Path, n: int = 3, seed: int = 1, timeout_s: float = 300.0,
                   part: tuple[int, int] = (0, 1), both: bool = False) -> list[dict]:
    """Every variant of :func:`_variants` on ``n`` random worlds and PAPF Tests I-VI.

    ``part = (k, K)``: only every K-th variant from the k-th, written to
    ``deviations-<k>.csv`` (split a long study over processes; concatenate the CSVs).

    Each of our deviations from the literal PAPF (:data:`DEVIATIONS`) switched *alone* — on
    top of ``--preset paper`` and off from the default.
    """
    from papf.console.progress import StepProgress
    from papf.experiments.paper_tests import PAPF_WORLDS, table2_check
    from papf.experiments.trials import markdown_table, run_offline, write_csv
    from papf.offline.world_gen import generate_solvable

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    worlds, _rejected = generate_solvable(n, seed)
    k, parts = part
    variants = _variants(both)[k::parts]
    rows = []
    with StepProgress("deviations", len(variants) * (len(worlds) + len(PAPF_WORLDS))) as bar:
        for label, sets in variants:
            rand = []
            for w in worlds:
                rand.append(run_offline(w, PAPF, seed, timeout_s, params=sets))
                bar.step(f"{label} on {w.name}: {rand[-1].outcome}")
            paper = []
            for w in PAPF_WORLDS:
                t = run_offline(w, PAPF, 0, timeout_s, params=sets)
                t.preset = "paper"   # table2_check looks rows up by label: give them one
                paper.append(t)
                bar.step(f"{label} on {w}: {t.outcome}")
            _reached, dur, path = table2_check(paper, "papf (paper)")
            rows.append({"variant": label, "group": _group(label),
                         "random_reached_pct": round(100.0 * sum(t.outcome == "reached" for t in rand) / len(rand), 1),
                         "random_collisions": sum(t.collisions for t in rand),
                         "tests_I_VI_reached": f"{sum(t.outcome == 'reached' for t in paper)}/{len(paper)}",
                         "tests_I_VI_duration_within_15pct": f"{dur}/{len(PAPF_WORLDS)}",
                         "tests_I_VI_path_within_10pct": f"{path}/{len(PAPF_WORLDS)}",
                         "tests_I_VI_duration_s": " ".join(f"{t.duration_s:.1f}" if t.outcome == "reached"
                                                           else t.outcome for t in paper),
                         "tests_I_VI_path_m": " ".join(f"{t.path_length_m:.2f}" if t.outcome == "reached"
                                                       else "-" for t in paper)})
    write_csv(rows, out / ("deviations.csv" if parts == 1 else f"deviations-{k}.csv"))
    replace_text((out / "deviations.md"),
        f"# PAPF deviations, each alone (offline; random set {seed}, {len(worlds)} worlds; PAPF "
        f"Tests I-VI seed 0)\n\n" + markdown_table(list(rows[0]), [list(r.values()) for r in rows]))
    return rows
