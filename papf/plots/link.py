"""``plot_link``: the link experiment's picture — the charge each planner drew over each link
(with and without an outage), and the delay sweep (``papf experiment link``)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402

from papf.plots.world import colour_for, saved_png  # noqa: E402


def _charges(ax, rows: Sequence[dict]) -> None:
    """Grouped bars: per link, one bar per (planner, outage); a run that did not reach its
    goal is drawn hollow and labelled with its outcome."""
    links = list(dict.fromkeys(r["link"] for r in rows))
    groups = list(dict.fromkeys((r["planner"], r["outage"]) for r in rows))
    width = 0.8 / max(len(groups), 1)
    planners = list(dict.fromkeys(p for p, _ in groups))
    for g, (planner, outage) in enumerate(groups):
        colour = colour_for(planner, planners.index(planner))
        for i, link in enumerate(links):
            r = next((r for r in rows if (r["planner"], r["outage"], r["link"]) == (planner, outage, link)), None)
            if r is None or not isinstance(r["charge_mAh"], (int, float)):
                continue
            x = i - 0.4 + width * (g + 0.5)
            reached = r["outcome"] == "reached"
            ax.bar(x, r["charge_mAh"], width, color=colour if reached else "none", edgecolor=colour,
                   hatch="//" if outage != "none" else None, alpha=0.9,
                   label=f"{planner}, outage {outage}" if i == 0 else None)
            if not reached:
                ax.text(x, r["charge_mAh"], r["outcome"], rotation=90, ha="center", va="bottom",
                        fontsize=7)
    ax.set_xticks(range(len(links)), links)
    ax.set_ylabel("charge to the outcome [mAh]")
    outages = sorted({o for _, o in groups if o != "none"})
    ax.set_title(f"charge per link (hatched: outage {', '.join(outages) or '-'}; hollow: goal "
                 "not reached)", fontsize=9)
    ax.legend(fontsize=7, frameon=False)


def _sweep(ax, rows: Sequence[dict]) -> None:
    """Time to the goal against the one-way delay; a run that did not reach it is an x on
    the top edge."""
    from matplotlib.transforms import blended_transform_factory

    top = blended_transform_factory(ax.transData, ax.transAxes)
    planners = list(dict.fromkeys(r["planner"] for r in rows))
    for k, planner in enumerate(planners):
        mine = sorted((r for r in rows if r["planner"] == planner),
                      key=lambda r: int(r["link"].removesuffix("ms")))
        ok = [(int(r["link"].removesuffix("ms")), r["duration_s"]) for r in mine
              if r["outcome"] == "reached"]
        colour = colour_for(planner, k)
        ax.plot([x for x, _ in ok], [y for _, y in ok], "o-", color=colour,
                label=f"{planner} (reached)")
        for r in mine:
            if r["outcome"] != "reached":
                ax.plot(int(r["link"].removesuffix("ms")), 0.97 - 0.05 * k, "x", color=colour,
                        ms=8, transform=top, clip_on=False)
    ax.set_xlabel("one-way delay [ms] (no jitter)")
    ax.set_ylabel("time to the goal [s]")
    ax.set_title("delay sweep (x at the top: goal not reached)", fontsize=9)
    ax.set_ylim(bottom=0)
    ax.legend(fontsize=7, frameon=False, loc="lower right")


def plot_link(profiles: Sequence[dict], sweep: Sequence[dict], out_png: str | Path) -> Path:
    """The link experiment's PNG: charges per link and, if there is one, the delay sweep."""
    panels = [p for p in ((_charges, profiles), (_sweep, sweep)) if p[1]]
    fig, axes = plt.subplots(1, max(len(panels), 1), figsize=(6.0 * max(len(panels), 1), 4.2),
                             layout="constrained", squeeze=False)
    with saved_png(fig, out_png) as out:
        for ax, (draw, rows) in zip(axes[0], panels, strict=False):
            draw(ax, rows)
    return out
