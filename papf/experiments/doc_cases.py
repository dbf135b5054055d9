"""``papf experiment cases``: the small studies behind the older tables of docs/planners.md.

Each study (:data:`STUDIES`) is a list of cases: a label, a planner, its settings, the worlds
and seeds, offline (:func:`papf.offline.run.simulate`) and/or through the stack (:func:`run_stack`). Every
run goes into ``OUT/cases-runs.csv``; each case's summary (reached k/n, ranges of duration,
path, clearance and charge over its runs) into ``OUT/<study>.csv``, the file a docs table
is generated from (``papf/doctools/tables.py``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from nodes.planner.registry import one_with_role

# the planners the papers' comparisons are about, by their declared roles (nodes/planner/registry.py)
APF = one_with_role("papf-baseline")
PAPF = one_with_role("papf-proposed")
ARAPF = one_with_role("arapf-proposed")
WANG = one_with_role("wang-proposed")

DEAD_ENDS = ("arapf-test-1", "arapf-test-2", "arapf-test-3", "papf-test-4", "papf-test-5")
WANG_WORLDS = ("wang-unreachable-goal", "wang-local-minimum")


@dataclass(frozen=True)
class Case:
    """One row of a study's table: ``planner`` with ``sets`` on ``worlds`` x ``seeds``."""

    label: str
    planner: str
    worlds: tuple[str, ...]
    sets: tuple[str, ...] = ()
    seeds: tuple[int, ...] = (0,)
    stack_seeds: tuple[int, ...] = ()     # also through the stack with these seeds
    offline: bool = True
    group_by_world: bool = True           # one summary row per world (else one per case)
    extra: dict = field(default_factory=dict)


def _arapf_ablation() -> list[Case]:
    changes = [("defaults", ()), ("range_limited=false", ("range_limited=false",)),
               ("wall_range_limited=false", ("wall_range_limited=false",)),
               ("follow=false", ("follow=false",)), ("passage_width=gap", ("passage_width=gap",))]
    changes += [(f"obstacle_offset_m={v}", (f"obstacle_offset_m={v}",))
                for v in (0.15, 0.2, 0.35, 0.4, 0.45, 0.5)]
    return [Case(label, ARAPF, DEAD_ENDS, sets, group_by_world=False) for label, sets in changes]


def _energy_stack() -> list[Case]:
    cases = [Case(p, p, ("energy",), offline=False, stack_seeds=(0,))
             for p in (APF, PAPF, ARAPF, WANG)]
    cases += [Case(f"{p} d_o={d}", p, ("energy",), (f"d_o={d}",), offline=False, stack_seeds=(0,))
              for d in (0.4, 0.3, 0.25) for p in (APF, PAPF)]
    return cases


STUDIES: dict[str, list[Case]] = {
    "arapf-ablation": _arapf_ablation(),
    "arapf-results": [Case(ARAPF, ARAPF, (*DEAD_ENDS, "energy"), stack_seeds=(0,))],
    "wang-ablation": [Case(label, WANG, WANG_WORLDS, (label,) if label != "defaults" else (),
                           seeds=tuple(range(8)))
                      for label in ("defaults", "control_offset_m=0", "control_offset_m=0.02",
                                    "control_offset_m=0.1", "control_offset_m=0.2",
                                    "control_offset_m=0.3", "k_rep_l=10")],
    "wang-results": [Case(WANG, WANG, WANG_WORLDS, seeds=tuple(range(8)), stack_seeds=(0,)),
                     Case(WANG, WANG, ("energy",), stack_seeds=(0,)),
                     Case(APF, APF, ("wang-unreachable-goal",), seeds=tuple(range(8)))],
    "energy-stack": _energy_stack(),
    "gap-push": [],       # a computation, no runs: gap_push_rows
}


GAP_WIDTHS = (0.45, 0.55, 0.6, 0.7, 0.8, 0.9)
GAP_D_OS = (0.25, 0.3, 0.35, 0.4, 0.5)


def gap_push_rows(k_vo: float = 10.0 / 300, step: float = 0.005) -> list[dict]:
    """docs/planners.md "Narrow passages": the largest push back along a gap's axis.

    A 0.1 m barrier across the x axis, its face 1 m ahead of the robot, with one gap of width
    ``g`` centred on the axis; one 300-beam scan from the robot (noise-free); a predicted point
    moving along the axis from the robot to 0.5 m past the barrier feels every scan point
    within ``d_o`` (eq. 2's obstacle term, k_VO = 10 / L). Row per gap: the largest backward
    (-x) component over the point's positions, per d_o.
    """
    import numpy as np

    from nodes.planner.core import scan_view
    from schemas.messages import Odometry
    from worlds.toy import box_segments, cast_scan, toy_world

    rows = []
    for g in GAP_WIDTHS:
        segs = box_segments(1.05, g / 2 + 1.5, 0.1, 3.0) + box_segments(1.05, -g / 2 - 1.5, 0.1, 3.0)
        view = scan_view(cast_scan(toy_world(segments=segs), 0.0, 0.0, 0.0),
                         Odometry(stamp_ns=0, x=0.0, y=0.0, yaw=0.0, v=0.0, w=0.0))
        row = {"gap_m": g}
        for d_o in GAP_D_OS:
            best = 0.0
            for x in np.arange(0.0, 1.6, step):
                r = np.array([x, 0.0]) - view.points
                d = np.sqrt(np.sum(r * r, axis=1))
                k = (d <= d_o) & (d > 1e-9)
                best = max(best, -float(k_vo * np.sum(r[k, 0] / d[k] ** 3)))
            row[f"d_o_{d_o}"] = round(best, 2)
        rows.append(row)
    return rows


def _span(values: Sequence[float], nd: int) -> str:
    """``"a"`` or ``"a-b"`` (min-max) of the finite values, ``""`` if none."""
    v = [x for x in values if x is not None and math.isfinite(x)]
    if not v:
        return ""
    lo, hi = round(min(v), nd), round(max(v), nd)
    return f"{lo:.{nd}f}" if lo == hi else f"{lo:.{nd}f}-{hi:.{nd}f}"


def summarize(study: str, case: Case, world: str, mode: str, trials: list) -> dict:
    """One summary row: reached k/n and the spans over the reached runs (all runs if none)."""
    ok = [t for t in trials if t.outcome == "reached"]
    use = ok or trials
    outcomes = sorted({t.outcome for t in trials})
    return {"study": study, "case": case.label, "planner": case.planner, "world": world,
            "mode": mode, "seeds": " ".join(str(t.seed) for t in trials),
            "reached": f"{len(ok)}/{len(trials)}", "outcomes": " ".join(outcomes),
            "collisions": sum(t.collisions for t in trials),
            "duration_s": _span([t.duration_s for t in use], 1),
            "path_m": _span([t.path_length_m for t in use], 2),
            "min_clearance_m": _span([t.min_clearance_m for t in use], 2),
            "charge_mAh": _span([t.charge_mAh for t in use], 1)}


def _runs(case: Case, world: str):
    """(mode, seed) pairs of one case on one world."""
    out = [("offline", s) for s in case.seeds] if case.offline else []
    return out + [("stack", s) for s in case.stack_seeds]


def run_cases(out: str | Path, studies: Sequence[str], timeout_s: float = 300.0) -> dict[str, list[dict]]:
    """Run ``studies``; write ``OUT/<study>.csv`` (summaries) and ``OUT/cases-runs.csv``."""
    from papf.experiments.trials import progress_bar, run_offline, run_stack, write_csv
    from worlds import world_path

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    if "gap-push" in studies:
        write_csv(gap_push_rows(), out / "gap-push.csv")
        studies = [s for s in studies if s != "gap-push"]
    total = sum(len(_runs(c, w)) for s in studies for c in STUDIES[s] for w in c.worlds)
    runs, summaries = [], {}
    with progress_bar() as bar:
        task = bar.add_task("cases", total=total)
        for study in studies:
            rows = []
            for case in STUDIES[study]:
                done: dict[tuple[str, str], list] = {}
                for world in case.worlds:
                    for mode, seed in _runs(case, world):
                        if mode == "offline":
                            t = run_offline(world, case.planner, seed, timeout_s, params=list(case.sets))
                        else:
                            args = [a for kv in case.sets for a in ("--set", kv)]
                            t = run_stack(world_path(world), case.planner, seed, timeout_s, planner_args=args)
                        bar.advance(task)
                        runs.append({"study": study, "case": case.label, **t.row()})
                        key = (world if case.group_by_world else "", mode)
                        done.setdefault(key, []).append(t)
                for (world, mode), trials in done.items():
                    label = world or " ".join(case.worlds)
                    rows.append(summarize(study, case, label, mode, trials))
            write_csv(rows, out / f"{study}.csv")
            summaries[study] = rows
    write_csv(runs, out / "cases-runs.csv")
    return summaries
