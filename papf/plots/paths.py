"""``plot_paths``: one PNG of a world and labelled paths — the figure of ``papf plan --plot``
(3-D worlds) and of the paper-tests and random-world experiments.

2-D worlds give a 2-D plot (equal axes, the world's extent, legend under the axes; see
:mod:`papf.plots.world`); 3-D worlds the 3-D view with top and side projections and the
clearance over time (:mod:`papf.plots.world3d`).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402

from papf.plots.world import (  # noqa: E402
    draw_paths,
    draw_world,
    new_axes,
    saved_png,
    set_view,
    view_extent,
)
from papf.plots.world3d import plot_paths_3d  # noqa: E402
from worlds import World  # noqa: E402


def plot_paths(world: World, paths: Mapping[str, np.ndarray], out_png: str | Path,
               title: str = "", times: Mapping[str, np.ndarray] | None = None) -> Path:
    """Save a PNG of ``world`` with every path of ``{label: (N, 2|3) array}``; returns the path.

    ``times`` (label -> (N,) [s]) dates the points of 3-D paths for the clearance plot.
    """
    if world.dims == 3:
        return plot_paths_3d(world, paths, out_png, title, times)
    fig, ax = new_axes(world)
    with saved_png(fig, out_png) as out:
        draw_world(ax, world)
        draw_paths(ax, paths, world.dims)
        set_view(ax, view_extent(world, paths.values()))
        ax.set_title(title or world.name)
        fig.legend(loc="outside lower center", ncol=min(len(paths) + 2, 4), fontsize=8,
                   frameon=False)
    return out
