"""``papf plan --plot`` on a car-scale road world: the road, the traffic over the run, the
path and the finish line — a road world's goal is "pass x = X" (papf/offline/road.py), so
the picture draws that line where the run ends, not a star in one lane.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from papf.plots.moment import draw_traffic, static_world  # noqa: E402
from papf.plots.world import (  # noqa: E402
    GOAL_COLOUR,
    START_COLOUR,
    colour_for,
    draw_obstacle,
    saved_png,
)
from worlds import World  # noqa: E402


def plot_road_run(world: World, planner: str, outcome: str, path: np.ndarray,
                  times: np.ndarray, out_png: str | Path, title: str) -> Path:
    """One road run: world, traffic over ``times``, the path (N, 2) [m] and the finish line."""
    fig, ax = plt.subplots(figsize=(11.0, 3.4), layout="constrained")
    with saved_png(fig, out_png) as out:
        for ob in static_world(world).obstacles:
            draw_obstacle(ax, ob, lw=0)
        draw_traffic(ax, world, float(times[-1]) if len(times) else 0.0)
        ax.plot(*world.start[:2], "o", color=START_COLOUR, ms=7, label="start", zorder=5)
        ax.axvline(world.goal[0], color=GOAL_COLOUR, lw=1.5, ls="--", zorder=4,
                   label=f"goal: the finish line x = {world.goal[0]:g} m")
        ax.plot(path[:, 0], path[:, 1], color=colour_for(planner, 0), lw=2.0, zorder=5,
                label=f"{planner} ({outcome}, {times[-1]:.1f} s)" if len(times) else planner)
        ax.plot(path[-1, 0], path[-1, 1], "o", color=colour_for(planner, 0), mec="k", zorder=6)
        ax.set_aspect("equal")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.grid(True, lw=0.3, alpha=0.5)
        ax.set_title(title)
        fig.legend(loc="outside lower center", ncol=3, fontsize=8, frameon=False)
        fit_height(fig, ax)
    return out


def fit_height(fig, ax, width_in: float | None = None, extra_in: float = 1.5) -> None:
    """Make ``fig`` as tall as its equal-aspect axes ``ax`` need at its width (or ``width_in``),
    plus ``extra_in`` for the title, the axis labels and a legend row: no empty band above and
    below a long, flat road."""
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    width = width_in or fig.get_figwidth()
    plot_w = width - 0.9                        # [in] less the y label and tick labels
    fig.set_size_inches(width, plot_w * abs(y1 - y0) / max(abs(x1 - x0), 1e-9) + extra_in)
