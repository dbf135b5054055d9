"""``papf report DIR|FILES...``: the energy report of recorded runs (:mod:`papf.report`).

Exit code 0 done, 2 bad input or an unreadable recording (a PapfError, printed by
:func:`papf.cli.main`).
"""

from __future__ import annotations

import json
import math

PROGRESS_AFTER_S = 3.0   # [s wall] a report done sooner prints no progress


def register(sub) -> None:
    """Add ``papf report`` and its options to the subcommands ``sub``."""
    p = sub.add_parser(
        "report", help="energy report of recorded runs (report.html, .md, .csv, PNGs)",
        description="Read MCAP recordings and rosbag2s recorded on the ROSbot only; write "
                    "report.md, report.csv, trajectories.png, charge.png, motion.png, mind.png and "
                    "report.html (all of it in one file a browser opens: figures embedded); an "
                    "existing report is refused before anything is computed (--force). Charge "
                    "and energy are re-metered from the recorded odometry and wheel states (a "
                    "bag's: from its odometry); a bag's /battery current gives the measured "
                    "charge beside them.")
    p.add_argument("inputs", nargs="+", metavar="DIR|FILE",
                   help="directories (every *.mcap and rosbag2 inside), .mcap files, rosbag2 "
                        "directories (metadata.yaml) or their .mcap / .db3")
    p.add_argument("--energy-model", choices=("paper", "motor"),
                   help="re-meter with this model (default: the model the live meter ran); "
                        "a re-metered report goes to its own files (report-paper.md, …)")
    p.add_argument("--out", metavar="DIR",
                   help="output directory (default: the one DIR given, else the first file's)")
    p.add_argument("--json", action="store_true", help="print per-run figures as JSON lines")
    p.add_argument("--force", action="store_true",
                   help="replace the report files of an earlier report in the output directory")
    add_topics_option(p)
    p.set_defaults(func=cmd_report)


def add_topics_option(p) -> None:
    """``--topics``: which topics of a rosbag2 are odometry, battery, commands, scans, TF."""
    p.add_argument("--topics", metavar="ROLE=/topic,...",
                   help="a rosbag2's topic names (default: the ROSbot's: "
                        "odom=/odometry/filtered,battery=/battery,cmd_vel=/cmd_vel,scan=/scan,"
                        "tf=/tf); roles not named keep their default")


def topic_map(args):
    """The parsed ``--topics`` (ConfigError: one line, exit 2)."""
    from papf.recording.rosbag import TopicMap

    return TopicMap.parse(getattr(args, "topics", None))


def cmd_report(args) -> int:
    """``papf report``: energy report of recorded runs; the exit code."""
    from common.text import safe_text
    from papf.console.progress import StepProgress
    from papf.report.metrics import BAG, live_difference, metadata_notes
    from papf.report.report import build_report  # matplotlib: only when reporting
    from papf.report.tables import bags_markdown, summary_markdown

    topics = topic_map(args)
    with StepProgress("report", 1, after_s=PROGRESS_AFTER_S) as progress:   # total: set by it
        report = build_report(args.inputs, args.out, args.energy_model, topics=topics,
                              progress=progress, force=args.force)
    if args.json:
        for m in report.runs:   # NaN -> null (JSON has no NaN)
            row = {**m.row(), **({"sides": m.sides} if m.sides else {})}
            print(json.dumps(finite(row), allow_nan=False))
        return 0
    def say(text: str) -> None:   # a recording's world, reason, notes: shown, never run
        print(safe_text(text, None, keep_newlines=True))

    say(f"{report.model_note}; {report.pose_note}")
    for m in report.runs:
        for line in [*metadata_notes(m), live_difference(m), sides_note(m)]:
            if line:
                say(line)
    bags = [r for r in report.runs if r.outcome == BAG]
    if bags:
        say("\nbags recorded on the robot:")
        show_table(bags_markdown(bags, report.model), say)
    bag_worlds = {r.world for r in bags}
    for world in sorted({s.world for s in report.summaries} - bag_worlds):
        say(f"\nworld {world}:")
        show_table(summary_markdown([s for s in report.summaries if s.world == world],
                                    report.model), say)
    say(f"\nwrote {', '.join(str(f) for f in report.files)}")
    page = next((f for f in report.files if f.suffix == ".html"), None)
    if page is not None:   # one file, figures inside: what a user opens first
        say(f"open {page.resolve().as_uri()} in a browser (one file, figures embedded)")
    return 0


def sides_note(m) -> str:
    """One line on a run recorded on both sides: where the figures came from, what the
    laptop missed."""
    if not m.sides:
        return ""
    s = m.sides
    holes = ", ".join(f"{a:.2f}-{b:.2f} s" for a, b in s["laptop_missed_s"])
    return (f"{m.file}: path, duration, charge and energy from the robot's recording "
            f"{s['robot_file']}; the laptop's recording missed "
            + (f"{s['laptop_missed_total_s']:.2f} s of odometry ({holes})" if holes else "nothing"))


def show_table(text: str, say) -> None:
    """A Markdown table of the report: on a terminal as a table that fits it
    (:func:`papf.console.tables.print_table`); piped, the Markdown lines as they are."""
    from rich.console import Console

    from papf.console.tables import markdown_table, print_table

    console = Console()
    table = markdown_table(text) if console.is_terminal else None
    if table is None:
        say(text)
    else:
        print_table(table, console)


def finite(obj):
    """``obj`` with every non-finite float (NaN, inf) as None, in dicts and lists."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: finite(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [finite(v) for v in obj]
    return obj
