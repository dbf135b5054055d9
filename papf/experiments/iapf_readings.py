"""``papf experiment iapf --readings``: what each of our readings of the IAPF paper changes.

Every case A-D runs with the default IAPF settings and then with one reading switched back
to the paper as printed (or one addition of ours switched off), plus the whole Table 1
literal preset and a sweep of the traditional baseline's ``k``. Writes ``readings.md``
and ``readings.csv`` into ``OUT`` (docs/planners.md, "IAPF", quotes them).
"""

from __future__ import annotations

import csv
from pathlib import Path

from common.outfiles import output, replace_text
from nodes.planner.iapf.algorithm import PAPER_PRESET
from papf.experiments.iapf import CASES, IAPF, IAPF_NP, TRADITIONAL
from papf.offline.run import simulate
from worlds import load_world

LEADER_C_KMH = 28.8      # case C's leader (Table 1 v_obs1.3)
FOLLOW_TOL_KMH = 3.6     # case C passes when the host ends within 1 m/s of it

# (label, planner, settings): one change against the defaults each
READINGS = [
    ("default (ours)", IAPF, []),
    ("Table 1 literal (--preset paper)", IAPF, [f"{k}={v}" for k, v in PAPER_PRESET.items()]),
    ("A_x = -0.15 (Table 1)", IAPF, ["a_x=-0.15"]),
    ("obstacle gain 1 (eq. 11 as printed)", IAPF, ["obstacle_gain=1"]),
    ("T_c = 0.4 s (Table 1)", IAPF, ["t_c=0.4"]),
    ("lane-goal half period d_w (eq. 8 as printed)", IAPF, ["goal_half_period_lanes=1"]),
    ("temporary goal b3 = 1.52 (Table 1 b3)", IAPF, ["b3_temp=1.52"]),
    ("heading unlimited (eq. 21 as printed)", IAPF, ["heading_max_deg=90", "yaw_rate_max_deg=0"]),
    ("rotation as printed (eq. 10)", IAPF, ["literal_rotation=true"]),
    ("prediction step 0.02 s (= t)", IAPF, ["predict_step_s=0.02"]),
    ("no safety cut-off (D_S >= 100 m, the largest S_m)", IAPF, ["s_m=100"]),
    ("no slow-leader lane change (Sec. 2.1 rule off)", IAPF, ["follow_min_frac=0"]),
    ("temporary goal b3 = 25 (below the ridge k2 d_w / sin 45 deg)", IAPF, ["b3_temp=25"]),
    ("stop law on (the planner node's 0.5)", IAPF, ["stop_decel_frac=0.5"]),
    ("slow tracks keep their own heading (eq. 10 phi as given)", IAPF, ["heading_min_speed=0"]),
    ("no prediction", IAPF_NP, []),
    ("traditional APF k = 200", TRADITIONAL, ["k_trad=200"]),
    ("traditional APF k = 1000", TRADITIONAL, ["k_trad=1000"]),
    ("traditional APF k = 3000 (default)", TRADITIONAL, []),
    ("traditional APF k = 10000", TRADITIONAL, ["k_trad=10000"]),
]


def _cell(run, case: str) -> str:
    """One case's outcome: collisions, off the road, lane changes (LC), case C's final speed;
    ok = what the paper shows IAPF doing (A, B, D: a lane change; C: following)."""
    bits = []
    if run.collisions:
        bits.append(f"{run.collisions} collision")
    if run.left_road:
        bits.append("off road")
    bits.append(f"{run.lane_changes} LC")
    if case == "iapf-case-c":
        bits.append(f"{3.6 * run.states[-1, 2]:.1f} km/h")
    follows = abs(3.6 * run.states[-1, 2] - LEADER_C_KMH) <= FOLLOW_TOL_KMH
    ok = not run.collisions and not run.left_road and (
        run.lane_changes == 0 and follows if case == "iapf-case-c" else run.lane_changes >= 1)
    return ("ok: " if ok else "FAIL: ") + ", ".join(bits)


def run_readings(out: str | Path, progress=None) -> list[dict]:
    """Run each of :data:`READINGS`, write paths and CSV into ``out``; the rows."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    worlds = {c: load_world(c) for c in CASES}
    for label, planner, sets in READINGS:
        row = {"reading": label, "planner": planner, "settings": " ".join(sets)}
        for case, duration in CASES.items():
            run = simulate(worlds[case], planner, sets, max_time_s=duration, whole_time=True).trace
            row[case] = _cell(run, case)
            row[f"{case}_min_clearance_m"] = round(run.min_clearance_m, 3)
        rows.append(row)
        if progress:
            progress(label)
    with output(out / "readings.csv", force=True) as _tmp, open(_tmp, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    head = ["reading", "settings", *(c[-1].upper() for c in CASES)]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        lines.append("| " + " | ".join([r["reading"], f"`{r['settings']}`" if r["settings"] else "",
                                         *(r[c] for c in CASES)]) + " |")
    replace_text((out / "readings.md"), "\n".join(lines) + "\n")
    return rows
