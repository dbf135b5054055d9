"""``report.md``: the report's text — a section per world, the model and pose source named."""

from __future__ import annotations

from papf.report import tables
from papf.report.metrics import BAG, OSCILLATION_W_RAD_S
from papf.report.sides import sides_markdown

DEFINITIONS = (
    "duration: first motion (|v| > 0.01 m/s) to the outcome; path: the pose source's path up "
    "to the outcome; mean P: energy / outcome time; ∫β² dt [rad²/s³] and ∫j² dt [m²/s⁵]: "
    "squared angular acceleration and linear jerk of the odometry over the motion; osc.: "
    f"sign changes of ω beyond ±{OSCILLATION_W_RAD_S} rad/s; live charge: the live meter's "
    "last recorded figure at or before the outcome; re-meter Δ: re-metered minus live "
    "charge at that stamp (0 = the live meter is reproduced exactly).")


def headline(report, world: str) -> str:
    apf, papf = report.summary(tables.BASELINE, world), report.summary(tables.PROPOSED, world)
    if apf is None or papf is None:
        return ""
    a, p = apf.stats["charge_mAh"], papf.stats["charge_mAh"]
    pct = tables.change_pct(a, p)
    if pct != pct:  # nan: a planner has no completed run
        return "**PAPF vs APF:** no comparison (a planner has no run that reached the goal).\n"
    verdict = "lower" if pct < 0 else "higher"
    return (f"**PAPF vs APF on {world}** ({report.model} model): mean charge {p.mean:.2f} vs "
            f"{a.mean:.2f} mAh — PAPF draws {abs(pct):.1f} % {verdict} (paper: "
            f"{tables.PAPER_CHARGE_MAH[tables.PROPOSED]} vs {tables.PAPER_CHARGE_MAH[tables.BASELINE]} mAh, "
            f"{tables.PAPER_CHARGE_CHANGE_PCT:+.1f} %).\n")


def _intro(report) -> list[str]:
    runs = report.runs
    worlds = tables.worlds_of(runs)
    where = (f"world `{worlds[0]}`" if len(worlds) == 1 else
             f"{len(worlds)} worlds ({', '.join(f'`{w}`' for w in worlds)}; each has its own "
             "section: runs of different worlds are never averaged together)")
    return [
        "# Energy report" + (f" (re-metered: {report.model} model)" if report.suffix else ""),
        "",
        f"{len(runs)} recorded runs on {where}.",
        "",
        f"- **{report.model_note}**. Charge and energy are computed from the recorded odometry "
        "and wheel states by that model (docs/energy.md); `--energy-model` re-meters with the "
        "other one into files of its own.",
        f"- **{report.pose_note}** — trajectories and path lengths.",
        "- Every figure comes from the MCAP files alone (`papf report`); definitions: "
        "docs/experiments-energy.md.",
        "",
        f"![charge per run, {report.model} model]({report.pngs[('charge', None)]})",
        "",
    ]


def _world_section(report, world: str) -> list[str]:
    mine = [s for s in report.summaries if s.world == world]
    runs = [r for r in report.runs if r.world == world]
    return [
        f"## World `{world}`",
        "",
        headline(report, world),
        f"### Per planner (runs that reached the goal: mean ± sd; {report.model} model)",
        "",
        tables.summary_markdown(mine, report.model),
        "",
        "### Comparison with the paper",
        "",
        tables.comparison_markdown(mine, report.model),
        "",
        "The paper's absolute charge (a real ROSbot, its own track, the charger's reading) is not "
        "comparable with a simulated run's; the relative change is.",
        "",
        "### Runs",
        "",
        tables.runs_markdown(runs, report.model),
        "",
        DEFINITIONS,
        "",
        f"![trajectories on {world}]({report.pngs[('trajectories', world)]})",
        "",
        "Motion (like the paper's Fig. 13):",
        "",
        f"![heading, v and ω over time on {world}]({report.pngs[('motion', world)]})",
        "",
        "The planner's mind (first run of each planner: prediction, abandoned predictions, top "
        "quarks, temporary goal, footprints):",
        "",
        f"![the planner's mind on {world}]({report.pngs[('mind', world)]})",
        "",
    ]


def _bags_section(report, bags: list) -> list[str]:
    lines = [
        "## Bags recorded on the robot",
        "",
        f"Re-metered from each bag's odometry ({report.model} model; wheel speeds and torques "
        "derived from it as the live ROSbot driver does, the pack's measured voltage from "
        "`/battery`) beside the charge measured by the robot: ∫ current dt of `/battery` over "
        "the odometry's span (ROS sign convention: negative current = discharge; none where "
        "the battery carries no current). Duration: first to last odometry sample moving "
        "faster than 0.01 m/s; path: the odometry's.",
        "",
        tables.bags_markdown(bags, report.model),
        "",
    ]
    for world in tables.worlds_of(bags):
        lines += [f"![path of {world}]({report.pngs[('trajectories', world)]})", "",
                  f"![heading, v and ω of {world}]({report.pngs[('motion', world)]})", ""]
    return lines


def _sides_section(runs: list) -> list[str]:
    return [
        "## Runs recorded on the laptop and on the robot",
        "",
        "The robot's own recording (`papf launch robot --record`) holds its odometry and wheels "
        "whatever the link did: path, duration, charge and energy come from it; outcome and "
        "reason from the laptop, where the run was judged. \"laptop missed\": intervals of the "
        "robot's odometry (run clock) that the laptop's recording does not hold.",
        "",
        sides_markdown(runs),
        "",
    ]


def markdown(report) -> str:
    lines = _intro(report)
    both = [r for r in report.runs if r.sides]
    if both:
        lines += _sides_section(both)
    bags = [r for r in report.runs if r.outcome == BAG]
    if bags:
        lines += _bags_section(report, bags)
    for world in tables.worlds_of([r for r in report.runs if r.outcome != BAG]):
        lines += _world_section(report, world)
    return "\n".join(lines)
