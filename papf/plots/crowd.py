"""``plot_crowd``: one PNG of a world with several robots' paths and the people's tracks
(``papf plan --plot`` on a world with ``[[robots]]`` or ``[[people]]``)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
from matplotlib.patches import Circle  # noqa: E402

from papf.plots.world import (  # noqa: E402
    draw_paths,
    draw_world,
    new_axes,
    saved_png,
    set_view,
    view_extent,
)
from worlds import World  # noqa: E402


def plot_crowd(world: World, robots: Mapping[str, np.ndarray], people: np.ndarray,
               radii: np.ndarray, out_png: str | Path, title: str = "") -> Path:
    """Robots' paths ``{label: (N, 2)}`` [m] and people's tracks ``(T, n, 2)`` [m] (grey,
    a dot at the start, the body's disc at the end); returns the PNG's path."""
    fig, ax = new_axes(world)
    with saved_png(fig, out_png) as out:
        draw_world(ax, world)
        for k in range(people.shape[1] if people.ndim == 3 else 0):
            track = people[:, k]
            ax.plot(track[:, 0], track[:, 1], color="0.55", lw=0.8, zorder=2,
                    label="people" if k == 0 else None)
            ax.plot(track[0, 0], track[0, 1], ".", color="0.4", ms=4, zorder=2)
            ax.add_patch(Circle(tuple(track[-1]), float(radii[k]), fc="0.85", ec="0.4",
                                lw=0.6, zorder=2))
        draw_paths(ax, robots, 2)
        tracks = [people[:, k] for k in range(people.shape[1])] if people.ndim == 3 else []
        set_view(ax, view_extent(world, [*robots.values(), *tracks]))
        ax.set_title(title or world.name)
        fig.legend(loc="outside lower center", ncol=min(len(robots) + 3, 4), fontsize=8,
                   frameon=False)
    return out
