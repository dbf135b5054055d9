"""``papf report DIR|FILES...`` and ``papf experiment energy`` (DESIGN.md §10).

Wire with ``register(subparsers)`` (adds ``report``, and ``energy`` under the
``experiment`` command of :func:`papf.plan_cli.experiment_parser` when that exists,
else under an ``experiment`` command of its own). Handlers return the exit code:
0 done, 2 bad input or unreadable recording (raised as PapfError, printed by papf.cli),
6 an experiment run failed or its report disagrees with the live figures.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path


def register(subparsers) -> None:
    """Add ``report`` and ``experiment energy`` to the ``papf`` subparsers."""
    add_report_parser(subparsers)
    register_experiment(_experiment_subparsers(subparsers))


def add_report_parser(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "report", help="energy report of recorded runs (report.md, report.csv, PNGs)",
        description="Read MCAP recordings only; write report.md, report.csv, trajectories.png, "
                    "charge.png and motion.png. Charge and energy are re-metered from the "
                    "recorded odometry and wheel states.")
    p.add_argument("inputs", nargs="+", metavar="DIR|FILE",
                   help="directories (every *.mcap inside) and/or .mcap files")
    p.add_argument("--energy-model", choices=("paper", "motor"),
                   help="re-meter with this model (default: the model the live meter ran)")
    p.add_argument("--out", metavar="DIR",
                   help="output directory (default: the one DIR given, else the first file's)")
    p.add_argument("--json", action="store_true", help="print per-run figures as JSON lines")
    p.set_defaults(func=cmd_report)
    return p


def register_experiment(experiment_subparsers) -> argparse.ArgumentParser:
    """Add ``energy`` to the ``experiment`` command's subparsers."""
    p = experiment_subparsers.add_parser(
        "energy", help="the PAPF paper's energy experiment (IV-C): planners x runs, recorded",
        description="World 'energy'; every planner x --runs, run k with seed S+k, each recorded "
                    "to OUT/<planner>-<k>.mcap through the whole process stack; then the "
                    "report in OUT.")
    add_energy_args(p)
    p.set_defaults(func=cmd_energy)
    return p


def add_energy_args(p: argparse.ArgumentParser) -> None:
    from papf.experiments.energy import TIMEOUT_S, WORLD

    p.add_argument("--runs", type=int, default=3, help="runs per planner (default 3)")
    p.add_argument("--planners", default="apf,papf", help="comma-separated (default apf,papf)")
    p.add_argument("--out", default="energy-experiment", metavar="DIR",
                   help="directory for the recordings and the report (default energy-experiment)")
    p.add_argument("--seed", type=int, default=0, help="base seed S: run k uses S+k (default 0)")
    p.add_argument("--world", default=WORLD, help=f"world (default {WORLD})")
    p.add_argument("--worlds", metavar="W1,W2",
                   help="several worlds, each into DIR/<world>/, plus DIR/energy-worlds.md/.csv "
                        "(e.g. energy,energy-blocking,energy-empty)")
    p.add_argument("--presets", default="default", metavar="P1,P2",
                   help="planner presets side by side: default, paper or default,paper")
    p.add_argument("--timeout", type=float, default=TIMEOUT_S, metavar="S",
                   help=f"sim-time limit per run [s] (default {TIMEOUT_S:g})")
    p.add_argument("--energy-model", choices=("motor", "paper"), default="motor",
                   help="the live meter's model (default motor)")


def _experiment_subparsers(subparsers):
    """The ``experiment`` command's subparsers: plan_cli's, an existing one, or our own."""
    try:
        from papf.plan_cli import experiment_parser
    except ImportError:
        experiment_parser = None
    if experiment_parser is not None:
        return experiment_parser(subparsers)
    existing = subparsers.choices.get("experiment")
    if existing is not None:  # registered by another module already: add to it
        for action in existing._actions:  # noqa: SLF001 - argparse keeps them there
            if isinstance(action, argparse._SubParsersAction):  # noqa: SLF001
                return action
    parser = subparsers.add_parser("experiment", help="run an experiment (many recorded runs)")
    return parser.add_subparsers(dest="experiment", required=True, metavar="EXPERIMENT")


def cmd_report(args: argparse.Namespace) -> int:
    from papf.report.report import build_report
    from papf.report.tables import summary_markdown

    report = build_report(args.inputs, args.out, args.energy_model)
    if args.json:
        for m in report.runs:
            print(json.dumps(m.row()))
        return 0
    print(summary_markdown(report.summaries))
    print(f"wrote {', '.join(str(f) for f in report.files)}")
    return 0


def cmd_energy(args: argparse.Namespace) -> int:
    from papf.experiments.energy import EnergyExperiment, run_experiment

    planners = tuple(p.strip() for p in args.planners.split(",") if p.strip())
    presets = tuple(p.strip() for p in args.presets.split(",") if p.strip())
    exp = EnergyExperiment(out=Path(args.out), runs=args.runs, planners=planners, seed=args.seed,
                           world=args.world, timeout_s=args.timeout,
                           energy_model=args.energy_model, presets=presets)
    if args.worlds:
        from papf.experiments.energy_worlds import run_energy_worlds

        worlds = [w.strip() for w in args.worlds.split(",") if w.strip()]
        results = run_energy_worlds(exp, worlds)
        for r in results:
            print_summary(r)
        print((Path(args.out) / "energy-worlds.md").read_text())
        return max(r.exit_code for r in results)
    result = run_experiment(exp)
    print_summary(result)
    return result.exit_code


def print_summary(res, console=None) -> None:
    """The experiment's table (mean ± sd), PAPF vs APF next to the paper, and the wall time."""
    from rich.console import Console
    from rich.table import Table

    from papf.report.report import REPORT_MD
    from papf.report.tables import PAPER, change_pct

    console = console or Console()
    t = Table(title="energy experiment (runs that reached the goal: mean ± sd)")
    for col in ("planner", "reached", "charge [mAh]", "energy [J]", "duration [s]", "path [m]"):
        t.add_column(col, justify="right")
    for s in res.report.summaries:
        st = s.stats
        t.add_row(s.planner, f"{s.reached}/{s.runs}", st["charge_mAh"].text(".2f"),
                  st["energy_J"].text(".1f"), st["duration_s"].text(".2f"),
                  st["path_length_m"].text(".3f"))
    console.print(t)
    apf, papf = res.report.summary("apf"), res.report.summary("papf")
    if apf and papf:
        for attr, label in (("charge_mAh", "charge"), ("duration_s", "duration"),
                            ("path_length_m", "path length")):
            console.print(f"PAPF vs APF {label}: {change_pct(apf.stats[attr], papf.stats[attr]):+.1f} %"
                          f"   paper: {PAPER[attr]}", highlight=False)
    for m in res.mismatches:
        console.print(f"[red]report differs from the live run:[/] {m}")
    console.print(f"report: {res.report.out_dir / REPORT_MD}")
    console.print(f"wall time: {res.wall_s:.1f} s for {len(res.results)} runs and the report",
                  highlight=False)
