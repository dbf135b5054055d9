"""``papf experiment wang``: Wang's Figs. 5-12 side by side with the paper's outcomes.

Each figure as published (a fixed-step point, :mod:`papf.offline.wang_step`) and on the
ROSbot (the ``wang-apf`` and ``wang`` planners), both through
:func:`papf.offline.run.simulate`; writes ``OUT/wang.md`` and ``OUT/wang.csv``.
"""

from __future__ import annotations

from pathlib import Path

from common.outfiles import replace_text
from nodes.planner.registry import one_with_role
from papf.experiments.trials import markdown_table, write_csv

# the planners the papers' comparisons are about, by their declared roles (nodes/planner/registry.py)
WANG = one_with_role("wang-proposed")
WANG_APF = one_with_role("wang-baseline")

#: (figure, world, method, the paper's outcome)
FIGURES = (
    ("Fig. 5", "wang-table1-fig5", "traditional", "fails (local minimum)"),
    ("Fig. 6", "wang-table1-fig5", "improved", "reached"),
    ("Fig. 7", "wang-table1-fig7", "traditional", "fails (oscillates at the target)"),
    ("Fig. 8", "wang-table1-fig7", "improved", "reached"),
    ("Fig. 5 (ROSbot world)", "wang-local-minimum", "traditional", "fails (local minimum)"),
    ("Fig. 6 (ROSbot world)", "wang-local-minimum", "improved", "reached"),
    ("Fig. 7 (ROSbot world)", "wang-unreachable-goal", "traditional", "fails (oscillates at the target)"),
    ("Fig. 8 (ROSbot world)", "wang-unreachable-goal", "improved", "reached"),
    ("Fig. 9", "wang-3d-fig9", "improved", "reached"),
    ("Fig. 10", "wang-3d-fig10", "improved", "reached"),
    ("Fig. 11", "wang-3d-fig11", "improved", "reached"),
    ("Fig. 12", "wang-3d-fig12", "improved", "fails"),
)
PLANNER = {"traditional": WANG_APF, "improved": WANG}
HEADER = ["figure", "world", "method", "paper", "fixed step (as published)", "iterations",
          "min clearance [units]", "ROSbot planner", "ROSbot outcome", "ROSbot path [m]"]


def run_wang(out: str | Path, seed: int = 0, timeout_s: float = 300.0) -> list[dict]:
    """Run every figure both ways; write ``wang.md`` and ``wang.csv`` into ``out``.

    Each figure is run twice:

    - **as published** — ``motion="fixed-step"`` (:mod:`papf.offline.wang_step`): a point stepping 0.5 along the
      force for at most J = 200 iterations, Table 1 gains, the obstacles' centres known
      (Wang's MATLAB simulation);
    - **on the ROSbot** — the default motion (offline; 2-D: simulated LiDAR and the
      ROSbot's motion law; 3-D: the point robot of :mod:`papf.offline.point3d`) with the registry's
      ``wang-apf`` (traditional, eqs. 1-5) or ``wang`` (improved, eqs. 6-8) planner.

    Both through :func:`papf.offline.run.simulate`.

    Writes ``OUT/wang.md`` and ``OUT/wang.csv``.
    """
    from papf.console.progress import StepProgress
    from papf.offline.run import simulate

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    with StepProgress("wang", len(FIGURES)) as progress:
        for fig, world, method, paper in FIGURES:
            fs = simulate(world, PLANNER[method], motion="fixed-step")
            robot = simulate(world, PLANNER[method], seed=seed, max_time_s=timeout_s)
            progress.step(f"fig {fig} {method}: published {fs.outcome}, rosbot {robot.outcome}")
            rows.append({"figure": fig, "world": world, "method": method, "paper": paper,
                         "fixed_step": fs.outcome, "iterations": fs.cycles,
                         "min_clearance": round(fs.min_clearance_m * fs.units_per_m, 3),
                         "planner": PLANNER[method],
                         "rosbot": robot.outcome, "rosbot_path_m": round(robot.length_m, 2)})
    write_csv(rows, out / "wang.csv")
    table = markdown_table(HEADER, [list(r.values()) for r in rows])
    replace_text((out / "wang.md"), f"# Wang's figures (seed {seed})\n\n{table}")
    return rows
