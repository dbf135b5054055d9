"""World and path plots (matplotlib, Agg backend: files only, no display).

- :func:`draw_world` — obstacles (boxes/walls as their footprints, cylinders as discs,
  spheres as wireframes on a 3-D axes), start and goal (with its tolerance) on an axes.
- :func:`plot_paths` — one figure: the world plus one line per labelled path, saved as PNG.
  2-D worlds give a 2-D plot (equal axes), 3-D worlds a 3-D axes.

Used by ``papf plan``, the paper-tests and random-world experiments and the energy report.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import Circle, Polygon  # noqa: E402

from worlds import World  # noqa: E402

OBSTACLE_COLOUR = "0.35"
GOAL_COLOUR = "tab:red"
START_COLOUR = "tab:green"
PATH_COLOURS = ("tab:blue", "tab:orange", "tab:purple", "tab:brown", "tab:pink", "tab:cyan",
                "tab:olive", "tab:gray")
PLANNER_COLOURS = {"apf": "tab:blue", "papf": "tab:orange", "arapf": "tab:purple",
                   "wang": "tab:brown"}


def new_axes(world: World, figsize=(7.0, 6.0)):
    """(figure, axes) suited to the world's dimension (3-D axes for 3-D worlds)."""
    fig = plt.figure(figsize=figsize)
    ax = fig.add_subplot(projection="3d") if world.dims == 3 else fig.add_subplot()
    return fig, ax


def draw_world(ax, world: World) -> None:
    """Obstacles, start and goal of ``world`` on ``ax`` (a 3-D axes for a 3-D world)."""
    if world.dims == 3:
        _draw_world_3d(ax, world)
        return
    for ob in world.obstacles:
        if ob.shape == "box":
            ax.add_patch(Polygon(ob.corners(), closed=True, color=OBSTACLE_COLOUR, lw=0))
        else:  # cylinder (or a sphere's footprint in a 2-D world)
            ax.add_patch(Circle(ob.center[:2], ob.radius, color=OBSTACLE_COLOUR, lw=0))
    sx, sy, yaw = world.start
    ax.plot(sx, sy, "o", color=START_COLOUR, ms=7, label="start", zorder=5)
    ax.annotate("", xy=(sx + 0.3 * np.cos(yaw), sy + 0.3 * np.sin(yaw)), xytext=(sx, sy),
                arrowprops={"arrowstyle": "->", "color": START_COLOUR}, zorder=5)
    gx, gy = world.goal[:2]
    ax.add_patch(Circle((gx, gy), world.tolerance, fill=False, color=GOAL_COLOUR, lw=1))
    ax.plot(gx, gy, "*", color=GOAL_COLOUR, ms=12, label="goal", zorder=5)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(True, lw=0.3, alpha=0.5)
    ax.autoscale_view()


def _draw_world_3d(ax, world: World) -> None:
    u, v = np.mgrid[0:2 * np.pi:24j, 0:np.pi:12j]
    for ob in world.obstacles:
        cx, cy, cz = ob.center[:3]
        r = ob.radius
        ax.plot_wireframe(cx + r * np.cos(u) * np.sin(v), cy + r * np.sin(u) * np.sin(v),
                          cz + r * np.cos(v), color=OBSTACLE_COLOUR, lw=0.4, alpha=0.6)
    ax.scatter(*world.start[:3], color=START_COLOUR, s=40, label="start")
    ax.scatter(*world.goal[:3], color=GOAL_COLOUR, marker="*", s=120, label="goal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    lo = np.min([world.start[:3], world.goal[:3]], axis=0)
    hi = np.max([world.start[:3], world.goal[:3]], axis=0)
    for ob in world.obstacles:
        lo = np.minimum(lo, np.array(ob.center[:3]) - ob.radius)
        hi = np.maximum(hi, np.array(ob.center[:3]) + ob.radius)
    span = float(np.max(hi - lo)) / 2 + 0.2
    mid = (lo + hi) / 2
    ax.set_xlim(mid[0] - span, mid[0] + span)
    ax.set_ylim(mid[1] - span, mid[1] + span)
    ax.set_zlim(mid[2] - span, mid[2] + span)


def colour_for(label: str, index: int) -> str:
    """A planner's fixed colour when the label starts with its name, else a cycling one."""
    head = label.split()[0].lower() if label else ""
    return PLANNER_COLOURS.get(head, PATH_COLOURS[index % len(PATH_COLOURS)])


def draw_paths(ax, paths: Mapping[str, np.ndarray], dims: int = 2) -> None:
    """One line per labelled path ((N, >=2) arrays [m]); the last point marked."""
    for i, (label, path) in enumerate(paths.items()):
        arr = np.asarray(path, dtype=float)
        if arr.size == 0:
            continue
        c = colour_for(label, i)
        if dims == 3:
            ax.plot(arr[:, 0], arr[:, 1], arr[:, 2], color=c, lw=1.6, label=label)
            ax.scatter(arr[-1, 0], arr[-1, 1], arr[-1, 2], color=c, marker="x", s=30)
        else:
            ax.plot(arr[:, 0], arr[:, 1], color=c, lw=1.6, label=label)
            ax.plot(arr[-1, 0], arr[-1, 1], "x", color=c, ms=7)


def plot_paths(world: World, paths: Mapping[str, np.ndarray], out_png: str | Path,
               title: str = "") -> Path:
    """Save a PNG of ``world`` with every path of ``{label: (N, 2|3) array}``; returns the path."""
    fig, ax = new_axes(world)
    try:
        draw_world(ax, world)
        draw_paths(ax, paths, world.dims)
        ax.set_title(title or world.name)
        ax.legend(loc="best", fontsize=8)
        out = Path(out_png)
        out.parent.mkdir(parents=True, exist_ok=True)
        fig.tight_layout()
        fig.savefig(out, dpi=110)
    finally:
        plt.close(fig)
    return out
