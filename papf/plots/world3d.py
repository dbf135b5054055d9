"""3-D plans (Wang's sphere worlds) on paper: a 3-D view, two projections and the clearance.

One 3-D perspective cannot show how close a path passes a sphere, so :func:`plot_paths_3d`
draws four panels: the 3-D view; the top projection (x-y) and the side projection (x-z),
each sphere as its outline circle in that plane (a path point inside the circle is not
necessarily inside the sphere — the clearance panel is the truth); and the clearance
over time, the distance from the point robot to the nearest sphere surface
(:func:`worlds.shapes.sphere_clearance`), with 0 marked — below it is a collision.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import Circle  # noqa: E402

from common.outfiles import output  # noqa: E402
from papf.plots.world import (  # noqa: E402
    GOAL_COLOUR,
    MARKERS,
    OBSTACLE_COLOUR,
    START_COLOUR,
    colour_for,
    draw_world,
    path_style,
)
from worlds import World  # noqa: E402
from worlds.shapes import sphere_clearance, spheres_of  # noqa: E402

PLANES = (("top (x-y)", 0, 1, "y [m]"), ("side (x-z)", 0, 2, "z [m]"))


def _bounds(world: World, paths: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    pts = [np.asarray(world.start[:3]), np.asarray(world.goal[:3])]
    for cx, cy, cz, r in spheres_of(world):
        pts += [np.array([cx, cy, cz]) - r, np.array([cx, cy, cz]) + r]
    pts += [p for a in paths if a.size for p in (a.min(axis=0), a.max(axis=0))]
    arr = np.array(pts)
    return arr.min(axis=0) - 0.3, arr.max(axis=0) + 0.3


def _projection(ax, world: World, paths: Mapping[str, np.ndarray], i: int, j: int,
                lo: np.ndarray, hi: np.ndarray, ylabel: str, title: str) -> None:
    for cx, cy, cz, r in spheres_of(world):
        c = (cx, cy, cz)
        ax.add_patch(Circle((c[i], c[j]), r, color=OBSTACLE_COLOUR, alpha=0.35, lw=0))
    ax.plot(world.start[i], world.start[j], "o", color=START_COLOUR, ms=7, zorder=6)
    ax.plot(world.goal[i], world.goal[j], "*", color=GOAL_COLOUR, ms=12, zorder=6)
    for k, (label, arr) in enumerate(paths.items()):
        if arr.size:
            c = colour_for(label, k)
            ax.plot(arr[:, i], arr[:, j], color=c, **path_style(k))
            ax.plot(arr[-1, i], arr[-1, j], MARKERS[k % len(MARKERS)], color=c, mec="k",
                    mew=0.5, ms=6, zorder=6)
    ax.set_xlim(lo[i], hi[i])
    ax.set_ylim(lo[j], hi[j])
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel("x [m]")
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.grid(True, lw=0.3, alpha=0.5)


def _clearance(ax, world: World, paths: Mapping[str, np.ndarray],
               times: Mapping[str, np.ndarray] | None) -> None:
    spheres = spheres_of(world)
    for k, (label, arr) in enumerate(paths.items()):
        if not arr.size:
            continue
        t = np.asarray(times[label]) if times and label in times else None
        x = t if t is not None and len(t) == len(arr) else np.arange(len(arr))
        ax.plot(x, [sphere_clearance(p, spheres) for p in arr], color=colour_for(label, k),
                label=label, **{**path_style(k), "lw": max(path_style(k)["lw"] - 1.0, 1.0)})
    ax.axhline(0.0, color="tab:red", lw=1.0, ls="--", label="surface (collision below)")
    ax.set_xlabel("time [s]" if times else "step")
    ax.set_ylabel("clearance to the nearest sphere [m]")
    ax.set_title("clearance over time", fontsize=10)
    ax.set_ylim(bottom=min(0.0, ax.get_ylim()[0]) - 0.05)
    ax.grid(True, lw=0.3, alpha=0.5)


def plot_paths_3d(world: World, paths: Mapping[str, np.ndarray], out_png: str | Path,
                  title: str = "", times: Mapping[str, np.ndarray] | None = None) -> Path:
    """Save the four-panel figure (module doc) of ``{label: (N, 3) array}``; returns the path."""
    arrays = {k: np.asarray(v, dtype=float).reshape(-1, 3) for k, v in paths.items()}
    lo, hi = _bounds(world, list(arrays.values()))
    fig = plt.figure(figsize=(12.0, 9.0), layout="constrained")
    try:
        ax3 = fig.add_subplot(2, 2, 1, projection="3d")
        draw_world(ax3, world)
        for k, (label, arr) in enumerate(arrays.items()):
            if arr.size:
                ax3.plot(arr[:, 0], arr[:, 1], arr[:, 2], color=colour_for(label, k), label=label,
                         lw=path_style(k)["lw"] * 0.6, ls=path_style(k)["ls"])
        ax3.set_title("3-D view", fontsize=10)
        for n, (name, i, j, ylabel) in enumerate(PLANES):
            _projection(fig.add_subplot(2, 2, 2 + n), world, arrays, i, j, lo, hi, ylabel,
                        f"{name} projection; spheres as outlines")
        _clearance(fig.add_subplot(2, 2, 4), world, arrays, times)
        fig.suptitle(title or world.name)
        fig.legend(*ax3.get_legend_handles_labels(), loc="outside lower center",
                   ncol=min(len(arrays) + 2, 4), fontsize=8, frameon=False)
        out = Path(out_png)
        out.parent.mkdir(parents=True, exist_ok=True)
        with output(out, force=True) as tmp:   # beside, then renamed (papf.plots.world.saved_png)
            fig.savefig(tmp, dpi=100, format="png")
    finally:
        plt.close(fig)
    return out
