"""``papf report DIR|FILES...``: the energy report of recorded runs (:mod:`papf.report`).

Exit code 0 done, 2 bad input or an unreadable recording (a PapfError, printed by
:func:`papf.cli.main`).
"""

from __future__ import annotations

import json


def register(sub) -> None:
    p = sub.add_parser(
        "report", help="energy report of recorded runs (report.md, report.csv, PNGs)",
        description="Read MCAP recordings only; write report.md, report.csv, trajectories.png, "
                    "charge.png and motion.png. Charge and energy are re-metered from the "
                    "recorded odometry and wheel states.")
    p.add_argument("inputs", nargs="+", metavar="DIR|FILE",
                   help="directories (every *.mcap inside) and/or .mcap files")
    p.add_argument("--energy-model", choices=("paper", "motor"),
                   help="re-meter with this model (default: the model the live meter ran); "
                        "a re-metered report goes to its own files (report-paper.md, …)")
    p.add_argument("--out", metavar="DIR",
                   help="output directory (default: the one DIR given, else the first file's)")
    p.add_argument("--json", action="store_true", help="print per-run figures as JSON lines")
    p.set_defaults(func=cmd_report)


def cmd_report(args) -> int:
    from papf.report.metrics import live_difference, metadata_notes
    from papf.report.report import build_report  # matplotlib: only when reporting
    from papf.report.tables import summary_markdown

    report = build_report(args.inputs, args.out, args.energy_model)
    if args.json:
        for m in report.runs:
            print(json.dumps(m.row()))
        return 0
    print(f"{report.model_note}; {report.pose_note}")
    for m in report.runs:
        for line in [*metadata_notes(m), live_difference(m)]:
            if line:
                print(line)
    for world in sorted({s.world for s in report.summaries}):
        print(f"\nworld {world}:")
        print(summary_markdown([s for s in report.summaries if s.world == world], report.model))
    print(f"\nwrote {', '.join(str(f) for f in report.files)}")
    return 0
