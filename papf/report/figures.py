"""The report's PNGs (matplotlib, Agg): trajectories, charge per run, Fig. 13-style motion.

- :func:`trajectories_png` — every run's ground-truth path over the world;
- :func:`charge_png` — charge per run as bars, with each planner's mean (line) and ± sd (band);
- :func:`motion_png` — heading, linear and angular velocity over time, one column per
  planner, like the subplots of the PAPF paper's Fig. 13.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from papf.plots import colour_for, draw_world  # noqa: E402
from papf.report.metrics import RunMetrics  # noqa: E402
from papf.report.tables import PlannerSummary, planner_order  # noqa: E402
from worlds import World  # noqa: E402

LINESTYLES = ("-", "--", ":", "-.")
DPI = 110


def _save(fig, path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    fig.savefig(path, dpi=DPI, bbox_inches="tight")
    plt.close(fig)
    return path


def _style(runs: Sequence[RunMetrics]) -> dict[str, tuple[str, str]]:
    """file -> (colour of its planner, line style of its index within the planner)."""
    out, count = {}, {}
    order = planner_order([r.planner for r in runs])
    for r in runs:
        k = count.get(r.planner, 0)
        count[r.planner] = k + 1
        out[r.file] = (colour_for(r.planner, order.index(r.planner)), LINESTYLES[k % len(LINESTYLES)])
    return out


def _label(r: RunMetrics) -> str:
    return f"{r.planner} seed {r.seed} ({r.outcome})"


def trajectories_png(runs: Sequence[RunMetrics], world: World | None, path: Path) -> Path:
    fig, ax = plt.subplots(figsize=(10.0, 4.8))
    if world is not None and world.dims == 2:
        draw_world(ax, world)
    style = _style(runs)
    for r in runs:
        if r.series is None or r.series.x.size == 0:
            continue
        colour, ls = style[r.file]
        ax.plot(r.series.x, r.series.y, color=colour, ls=ls, lw=1.4, label=_label(r))
        ax.plot(r.series.x[-1], r.series.y[-1], "x", color=colour, ms=6)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(True, lw=0.3, alpha=0.5)
    ax.set_title(f"trajectories{f' on {world.name}' if world else ''} (ground truth to the outcome)")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.3), ncol=3, fontsize=7, frameon=False)
    return _save(fig, path)


def charge_png(runs: Sequence[RunMetrics], summaries: Sequence[PlannerSummary],
               path: Path) -> Path:
    fig, ax = plt.subplots(figsize=(7.0, 4.2))
    style = _style(runs)
    x, ticks = 0.0, []
    for s in summaries:
        mine = [r for r in runs if r.planner == s.planner]
        xs = x + np.arange(len(mine))
        for xi, r in zip(xs, mine, strict=True):
            colour = style[r.file][0]
            ax.bar(xi, r.charge_mAh, color=colour, alpha=0.85 if r.outcome == "reached" else 0.3,
                   hatch=None if r.outcome == "reached" else "//", edgecolor="k", lw=0.5)
            ticks.append((xi, f"{r.planner}\nseed {r.seed}"))
        st = s.stats["charge_mAh"]
        if st.n:
            lo, hi = xs[0] - 0.45, xs[-1] + 0.45
            ax.hlines(st.mean, lo, hi, color="k", lw=1.5)
            if st.n > 1:
                ax.fill_between([lo, hi], st.mean - st.sd, st.mean + st.sd, color="k", alpha=0.12,
                                lw=0)
            ax.annotate(f"{st.text('.2f')} mAh", (np.mean(xs), st.mean), textcoords="offset points",
                        xytext=(0, 6), ha="center", fontsize=8)
        x = xs[-1] + 1.6 if len(xs) else x + 1.6
    ax.set_xticks([t for t, _ in ticks], [lab for _, lab in ticks], fontsize=8)
    top = max((r.charge_mAh for r in runs if np.isfinite(r.charge_mAh)), default=1.0)
    ax.set_ylim(0.0, 1.15 * top)
    ax.set_ylabel("charge drawn [mAh]")
    ax.set_title("charge per run; line = mean of reached runs, band = ± sd (hatched: not reached)",
                 fontsize=9)
    ax.grid(True, axis="y", lw=0.3, alpha=0.5)
    return _save(fig, path)


def motion_png(runs: Sequence[RunMetrics], path: Path) -> Path:
    planners = planner_order([r.planner for r in runs])
    rows = (("heading", "heading [deg]", np.degrees), ("v", "v [m/s]", None),
            ("w", "ω [rad/s]", None))
    fig, axes = plt.subplots(len(rows), max(len(planners), 1), sharex=True, sharey="row",
                             figsize=(5.0 * max(len(planners), 1), 6.5), squeeze=False)
    style = _style(runs)
    for col, planner in enumerate(planners):
        for r in (r for r in runs if r.planner == planner and r.series is not None):
            colour, ls = style[r.file]
            for row, (attr, _label_txt, conv) in enumerate(rows):
                y = getattr(r.series, attr)
                axes[row][col].plot(r.series.t_s, conv(y) if conv else y, color=colour, ls=ls,
                                    lw=0.9, label=f"seed {r.seed}")
        axes[0][col].set_title(planner.upper())
        axes[0][col].legend(fontsize=7, loc="best")
        axes[-1][col].set_xlabel("sim time [s]")
    for row, (_a, label, _c) in enumerate(rows):
        axes[row][0].set_ylabel(label)
        for ax in axes[row]:
            ax.grid(True, lw=0.3, alpha=0.5)
    return _save(fig, path)
