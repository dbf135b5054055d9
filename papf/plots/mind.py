"""The planner's mind on a matplotlib axes: what the PAPF paper drew in RViz.

- :func:`draw_footprint` — the ROSbot's chassis rectangle at a pose (``common.robot``);
- :func:`draw_mind` — one ``PlannerState``: predicted path, temporary goal, and the
  plug-in's own debug values (PAPF's top quarks and abandoned predictions, AR-APF's
  virtual walls, ...) drawn by kind in their declared style;
- :func:`snapshot_index` — the most telling cycle of a run (most debug points and paths,
  then the longest prediction) for a still picture;
- :func:`plot_plan` — ``papf plan --plot``: world, path, footprints along it, the mind at the
  snapshot cycle.

Colours are the live view's (:data:`nodes.viewer.scene.MIND_COLOURS`; the plug-in's own,
declared, for its debug values).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Polygon  # noqa: E402

from common.robot import BODY_LENGTH_M, BODY_WIDTH_M  # noqa: E402
from nodes.viewer.scene import MIND_COLOURS  # noqa: E402
from papf.plots.world import colour_for, draw_obstacle, draw_world, saved_png  # noqa: E402
from schemas.messages import PlannerState  # noqa: E402
from worlds import World  # noqa: E402

FOOTPRINT_EVERY_S = 2.0   # [s] of sim time between footprint outlines along a path


def rgba(name: str, alpha: float | None = None) -> tuple:
    r, g, b, a = MIND_COLOURS[name]
    return (r, g, b, a if alpha is None else alpha)


def footprint_corners(x: float, y: float, yaw: float) -> np.ndarray:
    """(4, 2) corners of the chassis rectangle at a pose [m]."""
    c, s = math.cos(yaw), math.sin(yaw)
    hx, hy = BODY_LENGTH_M / 2, BODY_WIDTH_M / 2
    local = np.array([(-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy)])
    return local @ np.array([[c, s], [-s, c]]) + (x, y)


def draw_footprint(ax, x: float, y: float, yaw: float, filled: bool = True, label=None):
    """The chassis at (x, y, yaw): filled (the robot now) or an outline (where it was)."""
    style = ({"facecolor": rgba("robot"), "edgecolor": rgba("robot", 1.0), "lw": 1.0}
             if filled else {"fill": False, "edgecolor": rgba("robot", 0.45), "lw": 0.6})
    patch = Polygon(footprint_corners(x, y, yaw), closed=True, zorder=6, label=label, **style)
    ax.add_patch(patch)
    nose = ax.plot([x, x + 0.6 * BODY_LENGTH_M * math.cos(yaw)],
                   [y, y + 0.6 * BODY_LENGTH_M * math.sin(yaw)], color=rgba("robot", 1.0),
                   lw=1.0 if filled else 0.5, zorder=6)
    return [patch, *nose]


def draw_road(ax, world: World) -> list:
    """The road's painted lines across the axes' x range: solid edges, dashed lane lines."""
    if world.road is None:
        return []
    out = []
    for rl in world.road.lines():
        out.append(ax.axhline(rl.y, color=rgba("road"), lw=1.5, zorder=1,
                              ls="-" if rl.kind == "solid" else (0, (6, 6))))
    return out


def draw_moving(ax, world: World, t_s: float) -> list:
    """The moving obstacles where they are at sim time ``t_s`` [s]."""
    out = []
    for ob in world.obstacles:
        if ob.motion is None:
            continue
        out.append(draw_obstacle(ax, ob.at(t_s), color=rgba("moving"), lw=0, zorder=4))
    return out


def draw_mind(ax, state: PlannerState, labels: bool = True) -> list:
    """Every piece of one planner cycle on ``ax``: the prediction and temporary goal every
    planner has, and the plug-in's own debug values by kind in their declared style;
    returns the artists (to remove later)."""
    lab = (lambda s: s) if labels else (lambda s: None)
    out = []
    if len(state.predicted_path) > 1:
        p = np.asarray(state.predicted_path)
        out += ax.plot(p[:, 0], p[:, 1], color=rgba("prediction"), lw=2.0, zorder=5,
                       label=lab("prediction"))
    for d in state.debug:
        out += _draw_debug(ax, d, lab)
    if len(state.temporary_goal) >= 2:
        tg = state.temporary_goal
        out += ax.plot(tg[0], tg[1], "D", color=rgba("temporary_goal"), ms=8, mec="k", mew=0.5,
                       zorder=7, label=lab("temporary goal"))
    return out


PT_PER_M = 60.0   # a debug style's size [m] in points: line widths and marker sizes alike


def _draw_debug(ax, d, lab) -> list:
    """One debug value by kind: points as dots, paths as lines (dashed if declared so),
    scalars and counts as words in the corner; the legend names it by its label."""
    out = []
    if d.kind in ("points", "point") and d.points:
        p = np.asarray(d.points)
        out += ax.plot(p[:, 0], p[:, 1], "o", color=d.colour, ms=max(3.0, d.size * PT_PER_M),
                       mec="k", mew=0.5, zorder=7, label=lab(d.caption))
    elif d.kind == "paths":
        drawn = [np.asarray(p) for p in d.paths if len(p) > 1]
        for i, p in enumerate(drawn):
            out += ax.plot(p[:, 0], p[:, 1], color=d.colour, lw=max(0.5, d.size * PT_PER_M),
                           ls="--" if d.dashed else "-", zorder=4 if d.dashed else 5,
                           label=lab(d.caption) if i == 0 else None)
    elif d.kind in ("scalar", "count") and not math.isnan(d.value):
        shown = sum(1 for a in ax.texts if getattr(a, "_papf_debug", False))
        t = ax.text(0.01, 0.01 + 0.045 * shown, d.words(), transform=ax.transAxes, fontsize=8,
                    color=d.colour[:3], zorder=8)
        t._papf_debug = True
        out.append(t)
    return out


def debug_handle(d):
    """A legend entry for debug value ``d`` as :func:`draw_mind` draws it (None: words only)."""
    if d.kind in ("points", "point"):
        return Line2D([], [], marker="o", ls="", color=d.colour, mec="k",
                      ms=max(3.0, d.size * PT_PER_M), label=d.caption)
    if d.kind == "paths":
        return Line2D([], [], color=d.colour, lw=max(0.5, d.size * PT_PER_M),
                      ls="--" if d.dashed else "-", label=d.caption)
    return None


def snapshot_index(states: Sequence[PlannerState]) -> int | None:
    """Index of the cycle showing most: the plug-in's debug points and paths first, then the
    longest prediction (the earliest of equals); None if no cycle shows anything."""
    best, best_score = None, (0, 0)
    for i, s in enumerate(states):
        score = (sum(len(d.points) + len(d.paths) for d in s.debug),
                 len(s.predicted_path) + (len(s.temporary_goal) >= 2))
        if score > best_score:
            best, best_score = i, score
    return best


def plot_plan(world: World, result, out_png: str | Path, title: str) -> Path:
    """``papf plan --plot``: the path, footprints every :data:`FOOTPRINT_EVERY_S`, and the
    mind and footprint at the snapshot cycle (named in the legend with its time)."""
    fig, ax = plt.subplots(figsize=(9.0, 6.0))
    with saved_png(fig, out_png) as out:
        draw_world(ax, world)
        path, t = result.path, result.times
        ax.plot(path[:, 0], path[:, 1], color=colour_for(result.planner, 0), lw=1.6,
                label=f"{result.planner} ({result.outcome})", zorder=3)
        next_t = 0.0
        for k in range(len(t)):
            if t[k] >= next_t:
                draw_footprint(ax, path[k, 0], path[k, 1], result.headings[k], filled=False)
                next_t = t[k] + FOOTPRINT_EVERY_S
        i = snapshot_index(result.states)
        if i is not None:
            state = result.states[i]
            draw_mind(ax, state)
            k = min(int(np.searchsorted(t, state.stamp_ns / 1e9)), len(t) - 1)
            draw_footprint(ax, path[k, 0], path[k, 1], result.headings[k],
                           label=f"robot at t = {state.stamp_ns / 1e9:.1f} s ({state.mode})")
        ax.set_title(title)
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
        ax.autoscale_view()
        fig.tight_layout()
    return out

