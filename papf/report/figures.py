"""The report's PNGs (matplotlib, Agg): trajectories, charge per run, Fig. 13-style motion.

Every figure names the energy model and the pose source in a footer line (the ``note``),
and one world per trajectory / motion figure: runs on different worlds never share axes.

- :func:`run_styles` — a run's colour (a shade of its planner's hue, darker per seed), dash
  and end marker, so seeds of one planner stay apart and planners stay recognisable;
- :func:`trajectories_png` — every run's path over the world's obstacles, the robot's
  footprint every metre and at the outcome, axes covering the world (never a thin strip),
  legend under the axes;
- :func:`charge_png` — charge per run as bars, each planner's mean (line) and ± sd (band),
  one panel per world;
- :func:`motion_png` — heading, linear and angular velocity over time, one column per
  planner, like the subplots of the PAPF paper's Fig. 13.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from nodes.planner.registry import declared  # noqa: E402
from papf.plots.moment import draw_traffic, static_world  # noqa: E402
from papf.plots.world import (  # noqa: E402
    LINESTYLES,
    MARKERS,
    draw_footprints,
    draw_world,
    set_view,
    view_extent,
)
from papf.report.metrics import BAG, RunMetrics, seed_text  # noqa: E402
from papf.report.tables import PlannerSummary, planner_order, worlds_of  # noqa: E402
from worlds import World  # noqa: E402

DPI = 110
PLANNER_MAPS = declared("colour_map")   # each planner's own (Strategy.colour_map)
OTHER_MAPS = ("Greys", "YlGn", "PuRd", "GnBu")


@dataclass(frozen=True)
class RunStyle:
    colour: tuple
    ls: str
    marker: str


def run_styles(runs: Sequence[RunMetrics]) -> dict[str, RunStyle]:
    """file -> style: the planner's hue, a darker shade, another dash and marker per run."""
    out = {}
    order = planner_order([r.planner for r in runs])
    for p_i, planner in enumerate(order):
        mine = sorted((r for r in runs if r.planner == planner), key=lambda r: (r.seed, r.file))
        cmap = plt.get_cmap(PLANNER_MAPS.get(planner, OTHER_MAPS[p_i % len(OTHER_MAPS)]))
        for k, r in enumerate(mine):
            shade = 0.75 if len(mine) == 1 else 0.45 + 0.5 * k / (len(mine) - 1)
            out[r.file] = RunStyle(cmap(shade), LINESTYLES[k % len(LINESTYLES)],
                                   MARKERS[k % len(MARKERS)])
    return out


def label(r: RunMetrics) -> str:
    """A run's legend entry: planner, seed, outcome; a fleet's robot named first."""
    own = f"{r.planner} seed {seed_text(r.seed)} ({r.outcome})"
    return f"{r.robot}: {own}" if r.robot else own


def _save(fig, path: Path, title: str, note: str) -> Path:
    """Title, then the note (energy model, pose source) in small grey under it; save; close."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.suptitle(f"{title}\n{note}" if note else title, fontsize=9.5)
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return path


def trajectories_png(runs: Sequence[RunMetrics], world: World | None, path: Path,
                     note: str = "", pose_source: str = "") -> Path:
    """Runs of one world over its obstacles (``world`` None: the paths alone)."""
    world = world if world is not None and world.dims == 2 else None
    arrays = [np.column_stack([r.series.x, r.series.y]) for r in runs
              if r.series is not None and r.series.x.size]
    extent = view_extent(world, arrays)
    aspect = (extent[3] - extent[2]) / (extent[1] - extent[0])
    h_world = min(max(10.0 * aspect, 3.0), 9.0)
    if len(arrays) > 1:   # a stretched copy tells close runs apart; one run's would magnify noise
        fig, (ax, ax_y) = plt.subplots(2, 1, figsize=(10.0, h_world + 4.2), layout="constrained",
                                       height_ratios=(h_world, 2.4))
    else:
        fig, ax = plt.subplots(figsize=(10.0, h_world + 1.6), layout="constrained")
        ax_y = None
    if world is not None:
        draw_world(ax, static_world(world))
        t_end = max((r.t_end_s for r in runs if math.isfinite(r.t_end_s)), default=0.0)
        draw_traffic(ax, world, t_end)    # road lines; each moving obstacle over the runs
    _draw_people(ax, runs, world)
    style = run_styles(runs)
    for r in runs:
        if r.series is None or r.series.x.size == 0:
            continue
        s = style[r.file]
        for a in (ax, ax_y) if ax_y is not None else (ax,):
            a.plot(r.series.x, r.series.y, color=s.colour, ls=s.ls, lw=1.6,
                   label=label(r) if a is ax else None, zorder=5)
            a.plot(r.series.x[-1], r.series.y[-1], s.marker, color=s.colour, mec="k", mew=0.5,
                   ms=7, zorder=6)
        draw_footprints(ax, r.series.x, r.series.y, r.series.heading, s.colour)
    set_view(ax, extent)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(True, lw=0.3, alpha=0.5)
    if ax_y is not None:
        ax_y.set_xlim(extent[0], extent[1])
        ax_y.set_xlabel("x [m]")
        ax_y.set_ylabel("y [m] (stretched)")
        ax_y.set_title("the same paths with y stretched, to tell close runs apart", fontsize=8.5)
        ax_y.grid(True, lw=0.3, alpha=0.5)
    world_name = world.name if world is not None else (runs[0].world if runs else "")
    fig.legend(loc="outside lower center", ncol=4, fontsize=8, frameon=False)
    return _save(fig, path, f"trajectories on {world_name} from {pose_source or 'the pose'}, "
                 "to each run's outcome; outlines: the robot's footprint every metre", note)


def _draw_people(ax, runs: Sequence[RunMetrics], world: World | None) -> None:
    """The people of the first run that recorded them (``sim/people``): the detours are
    explained by who was in the way (papf/plots/crowd.py draws them)."""
    from papf.plots.crowd import draw_people

    for r in runs:
        if r.series is not None and r.series.people is not None and len(r.series.people):
            shown = r.series.people_r
            draw_people(ax, world, r.series.people, shown.max(axis=0), shown)
            return


def charge_png(runs: Sequence[RunMetrics], summaries: Sequence[PlannerSummary], path: Path,
               note: str = "", model: str = "") -> Path:
    """Bars per run, one panel per world (charges of different worlds are not comparable)."""
    worlds = worlds_of(runs)
    fig, axes = plt.subplots(1, len(worlds), figsize=(max(7.0, 5.5 * len(worlds)), 4.6),
                             layout="constrained", squeeze=False)
    style = run_styles(runs)
    for ax, world in zip(axes[0], worlds, strict=True):
        _charge_panel(ax, [r for r in runs if r.world == world],
                      [s for s in summaries if s.world == world], style)
        ax.set_title(world, fontsize=10)
    axes[0][0].set_ylabel(f"charge drawn [mAh, {model} model]" if model else "charge drawn [mAh]")
    return _save(fig, path, "charge per run; line = mean of reached runs, band = ± sd "
                 "(hatched: not reached)", note)


def _charge_panel(ax, runs, summaries, style) -> None:
    x, ticks = 0.0, []
    for s in summaries:
        mine = [r for r in runs if r.planner == s.planner]
        xs = x + np.arange(len(mine))
        for xi, r in zip(xs, mine, strict=True):
            ok = r.outcome in ("reached", BAG)
            ax.bar(xi, r.charge_mAh, color=style[r.file].colour, alpha=0.9 if ok else 0.35,
                   hatch=None if ok else "//", edgecolor="k", lw=0.5)
            if r.measured_charge_mAh is not None:   # a bag's charge measured on the robot
                ax.plot(xi, r.measured_charge_mAh, "D", color="k", ms=6,
                        label="measured (/battery current)")
            ticks.append((xi, f"{r.planner}\nseed {seed_text(r.seed)}" if r.outcome != BAG
                          else r.file))
        st = s.stats["charge_mAh"]
        if st.n and len(xs):
            lo, hi = xs[0] - 0.45, xs[-1] + 0.45
            ax.hlines(st.mean, lo, hi, color="k", lw=1.5)
            if st.n > 1:
                ax.fill_between([lo, hi], st.mean - st.sd, st.mean + st.sd, color="k",
                                alpha=0.12, lw=0)
            ax.annotate(f"{st.text('.2f')} mAh", (np.mean(xs), st.mean),
                        textcoords="offset points", xytext=(0, 6), ha="center", fontsize=8)
        x = xs[-1] + 1.6 if len(xs) else x + 1.6
    ax.set_xticks([t for t, _ in ticks], [lab for _, lab in ticks], fontsize=8)
    top = max((c for r in runs for c in (r.charge_mAh, r.measured_charge_mAh or 0.0)
               if np.isfinite(c)), default=1.0)
    if any(r.measured_charge_mAh is not None for r in runs):
        handles, labels = ax.get_legend_handles_labels()
        ax.legend(handles[:1], labels[:1], fontsize=8, loc="lower right")
    ax.set_ylim(0.0, 1.18 * top if top > 0 else 1.0)
    ax.grid(True, axis="y", lw=0.3, alpha=0.5)


def motion_png(runs: Sequence[RunMetrics], path: Path, note: str = "") -> Path:
    """Heading, v and ω over sim time of one world's runs, a column per planner."""
    planners = planner_order([r.planner for r in runs])
    rows = (("heading", "heading [deg]", np.degrees), ("v", "v [m/s]", None),
            ("w", "ω [rad/s]", None))
    fig, axes = plt.subplots(len(rows), max(len(planners), 1), sharex=True, sharey="row",
                             figsize=(5.0 * max(len(planners), 1), 7.0), squeeze=False,
                             layout="constrained")
    style = run_styles(runs)
    for col, planner in enumerate(planners):
        for r in (r for r in runs if r.planner == planner and r.series is not None):
            s = style[r.file]
            for row, (attr, _txt, conv) in enumerate(rows):
                y = getattr(r.series, attr)
                axes[row][col].plot(r.series.t_s, conv(y) if conv else y, color=s.colour,
                                    ls=s.ls, lw=1.0, label=f"seed {seed_text(r.seed)}")
        axes[0][col].set_title(planner.upper())
        if axes[0][col].lines:
            axes[0][col].legend(fontsize=7, loc="best")
        axes[-1][col].set_xlabel("sim time [s]")
    for row, (_a, text, _c) in enumerate(rows):
        axes[row][0].set_ylabel(text)
        for ax in axes[row]:
            ax.grid(True, lw=0.3, alpha=0.5)
    return _save(fig, path, f"motion on {runs[0].world if runs else '?'} (odometry)", note)
