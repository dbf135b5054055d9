"""World and path plots (matplotlib, Agg backend: files only, no display).

- :func:`draw_world` — obstacles (each kind's footprint, :func:`draw_obstacle`;
  spheres as wireframes on a 3-D axes), start and goal (with its tolerance) on an axes.
- :func:`path_style` — line width, dash and end marker of the i-th path, so paths that lie
  on top of each other stay visible (the first is widest and underneath);
- :func:`view_extent` / :func:`set_view` — axes limits covering the world and every path,
  padded, never a thin strip (a straight run gets a span of at least ``MIN_RATIO``);
- :func:`footprint_corners` / :func:`draw_footprints` — the ROSbot's chassis rectangle
  (``common.robot``) at poses along a path.

Used by ``papf plan``, the paper-tests and random-world experiments and the energy report.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator, Mapping
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import ListedColormap  # noqa: E402
from matplotlib.patches import Circle, Polygon  # noqa: E402
from matplotlib.transforms import Affine2D  # noqa: E402

from common.outfiles import output  # noqa: E402
from common.robot import BODY_LENGTH_M, BODY_WIDTH_M  # noqa: E402
from nodes.planner.registry import declared  # noqa: E402
from worlds import Obstacle, World  # noqa: E402
from worlds.kinds.base import Disc, Outline, Raster  # noqa: E402

OBSTACLE_COLOUR = "0.35"
GOAL_COLOUR = "tab:red"
START_COLOUR = "tab:green"
PATH_COLOURS = ("tab:blue", "tab:orange", "tab:purple", "tab:brown", "tab:pink", "tab:cyan",
                "tab:olive", "tab:gray")
LINESTYLES = ("-", "--", "-.", ":")
MARKERS = ("o", "s", "^", "D", "v", "P")
PAD_M = 0.4            # [m] margin around the world and the paths
MIN_RATIO = 0.35       # [-] the shorter side of a view spans at least this much of the longer
FOOTPRINT_EVERY_M = 1.0   # [m] of path between footprint outlines
PLANNER_COLOURS = declared("colour")   # each planner's own (Strategy.colour), others by index


def new_axes(world: World, figsize=(7.0, 6.0)):
    """(figure, axes) suited to the world's dimension (3-D axes for 3-D worlds)."""
    fig = plt.figure(figsize=figsize, layout="constrained")
    ax = fig.add_subplot(projection="3d") if world.dims == 3 else fig.add_subplot()
    return fig, ax


def draw_world(ax, world: World) -> None:
    """Obstacles, start and goal of ``world`` on ``ax`` (a 3-D axes for a 3-D world)."""
    if world.dims == 3:
        _draw_world_3d(ax, world)
        return
    for ob in world.obstacles:
        draw_obstacle(ax, ob, color=OBSTACLE_COLOUR, lw=0)
    # a fleet: every robot's start (named) and goal, labelled once
    ends = [(r.start, r.goal, r.tolerance, r.name) for r in world.robots] or \
        [(world.start, world.goal[:2], world.tolerance, "")]
    for k, ((sx, sy, yaw), (gx, gy), tol, name) in enumerate(ends):
        ax.plot(sx, sy, "o", color=START_COLOUR, ms=7, label=None if k else "start", zorder=5)
        ax.annotate("", xy=(sx + 0.3 * np.cos(yaw), sy + 0.3 * np.sin(yaw)), xytext=(sx, sy),
                    arrowprops={"arrowstyle": "->", "color": START_COLOUR}, zorder=5)
        if name:
            ax.annotate(name, (sx, sy), xytext=(-4, 6), textcoords="offset points",
                        ha="right", fontsize=8, color=START_COLOUR, zorder=5)
        ax.add_patch(Circle((gx, gy), tol, fill=False, color=GOAL_COLOUR, lw=1))
        ax.plot(gx, gy, "*", color=GOAL_COLOUR, ms=12, label=None if k else "goal", zorder=5)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(True, lw=0.3, alpha=0.5)
    ax.autoscale_view()


def draw_obstacle(ax, ob: Obstacle, color=OBSTACLE_COLOUR, zorder: float = 1, **style):
    """An obstacle's footprint (its kind's drawing) on ``ax``; returns the artist."""
    shape = ob.model.drawing(ob)
    if isinstance(shape, Outline):
        return ax.add_patch(Polygon(shape.points, closed=True, color=color, zorder=zorder, **style))
    if isinstance(shape, Disc):
        return ax.add_patch(Circle(shape.center, shape.radius, color=color, zorder=zorder, **style))
    if isinstance(shape, Raster):
        return _draw_raster(ax, shape, color, zorder)
    raise TypeError(f"no top view for a {type(shape).__name__} drawing ({ob.kind})")


def _draw_raster(ax, r: Raster, color, zorder: float):
    """Wall cells as an image in the map's frame (turned by its yaw about its origin)."""
    rows, cols = r.cells.shape
    x0, y0 = r.origin
    img = ax.imshow(np.ma.masked_where(~r.cells, r.cells), cmap=ListedColormap([color]),
                    origin="lower", interpolation="nearest", zorder=zorder,
                    extent=(x0, x0 + cols * r.resolution, y0, y0 + rows * r.resolution))
    if r.yaw:
        img.set_transform(Affine2D().rotate_around(x0, y0, r.yaw) + ax.transData)
    return img


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


def path_style(i: int) -> dict:
    """Matplotlib line keywords of the i-th path: wide solid underneath, narrower dashes on top."""
    return {"lw": max(3.2 - 0.6 * i, 1.1), "ls": LINESTYLES[i % len(LINESTYLES)],
            "zorder": 3 + 0.1 * i, "solid_capstyle": "butt"}


def view_extent(world: World | None, paths=(), pad: float = PAD_M,
                min_ratio: float = MIN_RATIO) -> tuple[float, float, float, float]:
    """(x0, x1, y0, y1) [m] covering the world's start, goal, obstacles and every path."""
    xs, ys = [], []
    if world is not None:
        xs += [world.start[0], world.goal[0]] + [v for r in world.robots
                                                  for v in (r.start[0], r.goal[0])]
        ys += [world.start[1], world.goal[1]] + [v for r in world.robots
                                                  for v in (r.start[1], r.goal[1])]
        for ob in world.obstacles_at(0.0):
            x0, y0, x1, y1 = ob.model.bounds(ob)
            xs += [x0, x1]
            ys += [y0, y1]
    for arr in paths:
        arr = np.asarray(arr, dtype=float)
        if arr.size:
            xs += [float(np.nanmin(arr[:, 0])), float(np.nanmax(arr[:, 0]))]
            ys += [float(np.nanmin(arr[:, 1])), float(np.nanmax(arr[:, 1]))]
    if not xs:
        return (-1.0, 1.0, -1.0, 1.0)
    x0, x1, y0, y1 = min(xs) - pad, max(xs) + pad, min(ys) - pad, max(ys) + pad
    w, h = x1 - x0, y1 - y0
    if h < min_ratio * w:
        y0, y1 = (y0 + y1 - min_ratio * w) / 2, (y0 + y1 + min_ratio * w) / 2
    elif w < min_ratio * h:
        x0, x1 = (x0 + x1 - min_ratio * h) / 2, (x0 + x1 + min_ratio * h) / 2
    return x0, x1, y0, y1


def set_view(ax, extent: tuple[float, float, float, float]) -> None:
    ax.set_xlim(extent[0], extent[1])
    ax.set_ylim(extent[2], extent[3])
    ax.set_aspect("equal", adjustable="box")


def footprint_corners(x: float, y: float, yaw: float) -> np.ndarray:
    """(4, 2) corners of the ROSbot's chassis rectangle at a pose [m] (common.robot)."""
    c, s = np.cos(yaw), np.sin(yaw)
    hx, hy = BODY_LENGTH_M / 2, BODY_WIDTH_M / 2
    local = np.array([(-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy)])
    return local @ np.array([[c, s], [-s, c]]) + (x, y)


def draw_footprints(ax, x, y, yaw, colour, every_m: float = FOOTPRINT_EVERY_M) -> None:
    """Chassis outlines every ``every_m`` of path, and the final pose filled."""
    x, y, yaw = (np.asarray(a, dtype=float) for a in (x, y, yaw))
    if x.size == 0:
        return
    travelled = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(y)))])
    marks = np.searchsorted(travelled, np.arange(0.0, travelled[-1], every_m))
    for k in marks:
        ax.add_patch(Polygon(footprint_corners(x[k], y[k], yaw[k]), closed=True, fill=False,
                             edgecolor=colour, lw=0.6, alpha=0.7, zorder=4))
    ax.add_patch(Polygon(footprint_corners(x[-1], y[-1], yaw[-1]), closed=True, facecolor=colour,
                         edgecolor="k", lw=0.6, alpha=0.6, zorder=4))


def draw_paths(ax, paths: Mapping[str, np.ndarray], dims: int = 2) -> None:
    """One line per labelled path ((N, >=2) arrays [m]); the last point marked."""
    for i, (label, path) in enumerate(paths.items()):
        arr = np.asarray(path, dtype=float)
        if arr.size == 0:
            continue
        c = colour_for(label, i)
        style, marker = path_style(i), MARKERS[i % len(MARKERS)]
        if dims == 3:
            ax.plot(arr[:, 0], arr[:, 1], arr[:, 2], color=c, label=label, **style)
            ax.scatter(arr[-1, 0], arr[-1, 1], arr[-1, 2], color=c, marker=marker, s=30)
        else:
            ax.plot(arr[:, 0], arr[:, 1], color=c, label=label, **style)
            ax.plot(arr[-1, 0], arr[-1, 1], marker, color=c, mec="k", mew=0.5, ms=7,
                    zorder=style["zorder"] + 1)


@contextlib.contextmanager
def saved_png(fig, out_png: str | Path, dpi: int = 110) -> Iterator[Path]:
    """Draw on ``fig`` inside the block; when it completes, write ``out_png`` (its folder
    made); close ``fig`` whatever happens. Yields the PNG's path.

    Written beside and renamed into place, a symlink replaced and never followed
    (:func:`common.outfiles.output`); whether an existing file may be replaced is the
    caller's check, made before the work (``papf plan --plot``: ``--force``)."""
    out = Path(out_png)
    try:
        yield out
        out.parent.mkdir(parents=True, exist_ok=True)
        with output(out, force=True) as tmp:
            fig.savefig(tmp, dpi=dpi, format="png")
    finally:
        plt.close(fig)
