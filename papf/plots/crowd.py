"""Crowd pictures, the people always drawn (a detour is explained by who was in the way).

- :func:`plot_crowd`: one world with several robots' paths and the people (``papf plan
  --plot`` on a world with ``[[robots]]``, ``[[people]]`` or ``[[people_replay]]``);
- :func:`plot_crowd_scenes`: the crowd experiment's scenes of one seed, a panel each, every
  planner's path among the people (``crowd-scenes.png``);
- :func:`plot_crowd_summary`: the experiment's figures per planner and scene with their 95 %
  intervals (``crowd.png``).

How people are drawn (:func:`draw_people`): a walking person's track as a grey line (only
while in the scene: a replayed person comes and goes), a dot where it was first seen, its
body's disc where it was last; a standing person as a filled disc with a dark edge; a group
as the outline of its members' space (the convex hull of their centres grown by their radius,
common/crowd_social.py), dashed. Times when a robot passed close are left to the animation
(``papf animate``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import Circle, Polygon  # noqa: E402

from papf.plots.world import (  # noqa: E402
    colour_for,
    draw_paths,
    draw_world,
    new_axes,
    saved_png,
    set_view,
    view_extent,
)
from worlds import World  # noqa: E402

TRACK_COLOUR = "0.6"
STANDING_COLOUR = "0.75"


def _hull_outline(centres: np.ndarray, radius: float) -> np.ndarray:
    """Points of the boundary of the hull of ``centres`` grown by ``radius`` [m]."""
    a = np.linspace(0.0, 2 * np.pi, 24, endpoint=False)
    ring = np.column_stack([np.cos(a), np.sin(a)]) * radius
    pts = (centres[:, None, :] + ring[None, :, :]).reshape(-1, 2)
    from common.crowd_social import convex_hull

    return convex_hull(pts)


def draw_people(ax, world: World | None, people: np.ndarray, radii: np.ndarray,
                shown: np.ndarray | None = None) -> list:
    """The people of a run on ``ax`` (module doc): ``people`` (T, n, 2) [m], ``radii`` (n,)
    [m], ``shown`` (T, n) [m] each one's radius at each time (0: not in the scene); the
    ``world`` says who stands and the groups (None: nobody, none). Returns the legend's
    handles."""
    from matplotlib.lines import Line2D

    people = np.asarray(people, float).reshape(-1, len(radii), 2) if len(radii) else \
        np.zeros((0, 0, 2))
    if not people.size:
        return []
    here = np.ones(people.shape[:2], bool) if shown is None else np.asarray(shown) > 0
    specs = world.people if world is not None else ()
    groups = world.groups if world is not None else ()
    standing = [k < len(specs) and specs[k].standing for k in range(people.shape[1])]
    for k in range(people.shape[1]):
        idx = np.flatnonzero(here[:, k])
        if not len(idx):
            continue
        xy = people[idx, k]
        if standing[k]:
            ax.add_patch(Circle(tuple(xy[0]), float(radii[k]), fc=STANDING_COLOUR, ec="0.25",
                                lw=0.8, zorder=2))
            continue
        ax.plot(xy[:, 0], xy[:, 1], color=TRACK_COLOUR, lw=0.7, zorder=2)
        ax.plot(*xy[0], ".", color="0.45", ms=3, zorder=2)
        ax.add_patch(Circle(tuple(xy[-1]), float(radii[k]), fc="0.88", ec="0.45", lw=0.5,
                            zorder=2))
    for g in groups:
        members = np.array(g.members)
        centres = people[0, members] if g.standing(specs) else people[-1, members]
        ax.add_patch(Polygon(_hull_outline(centres, float(np.mean(radii[members]))),
                             closed=True, fill=False, ec="0.2", lw=0.9, ls="--", zorder=2))
    handles = [Line2D([], [], color=TRACK_COLOUR, lw=0.9, label="people walking")]
    if any(standing):
        handles.append(Line2D([], [], ls="", marker="o", mfc=STANDING_COLOUR, mec="0.25",
                              label="standing"))
    if groups:
        handles.append(Line2D([], [], color="0.2", ls="--", lw=0.9, label="group's space"))
    return handles


def plot_crowd(world: World, robots: Mapping[str, np.ndarray], people: np.ndarray,
               radii: np.ndarray, out_png: str | Path, title: str = "",
               shown: np.ndarray | None = None) -> Path:
    """Robots' paths ``{label: (N, 2)}`` [m] and the people (:func:`draw_people`); the PNG."""
    fig, ax = new_axes(world)
    with saved_png(fig, out_png) as out:
        draw_world(ax, world)
        handles = draw_people(ax, world, people, radii, shown)
        draw_paths(ax, robots, 2)
        tracks = [people[:, k] for k in range(people.shape[1])] if people.ndim == 3 else []
        set_view(ax, view_extent(world, [*robots.values(), *tracks]))
        ax.set_title(title or world.name)
        lines, labels = ax.get_legend_handles_labels()
        fig.legend(lines + handles, labels + [h.get_label() for h in handles],
                   loc="outside lower center", ncol=min(len(robots) + len(handles), 5),
                   fontsize=8, frameon=False)
    return out


def plot_crowd_scenes(scenes: Sequence[dict], out_png: str | Path) -> Path | None:
    """One panel per scene: ``world``, ``label``, ``paths`` {planner: (N, 2)}, ``people``
    (T, n, 2), ``shown`` (T, n) (module doc)."""
    if not scenes:
        return None
    cols = min(len(scenes), 3)
    rows = -(-len(scenes) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(5.2 * cols, 4.3 * rows), squeeze=False,
                             layout="constrained")
    handles: dict = {}
    with saved_png(fig, out_png) as out:
        for ax, scene in zip(axes.flat, scenes, strict=False):
            world = scene["world"]
            people = np.asarray(scene["people"], float)
            shown = np.asarray(scene["shown"], float)
            radii = shown.max(axis=0) if shown.size else np.zeros(0)
            draw_world(ax, world)
            for h in draw_people(ax, world, people, radii, shown):
                handles.setdefault(h.get_label(), h)
            paths = {k: np.asarray(v, float) for k, v in scene["paths"].items()}
            draw_paths(ax, paths, 2)
            set_view(ax, view_extent(world, list(paths.values())))
            ax.set_title(scene["label"], fontsize=10)
        for ax in list(axes.flat)[len(scenes):]:
            ax.axis("off")
        lines, labels = axes.flat[0].get_legend_handles_labels()
        fig.legend(lines + list(handles.values()), labels + list(handles),
                   loc="outside lower center", ncol=min(len(lines) + len(handles), 8),
                   fontsize=8, frameon=False)
    return out


SUMMARY_PANELS = (("reached", "success [%]"), ("min_separation_m", "min separation [m]"),
                  ("personal_s", "someone within 1.2 m [s]"),
                  ("group_intrusions", "group intrusions"), ("min_ttc_s", "min TTC [s]"),
                  ("people_time_ext_s", "people's extra time [s]"))


def plot_crowd_summary(summary: Sequence[dict], out_png: str | Path) -> Path:
    """The experiment's figures (:data:`SUMMARY_PANELS`) as bars per scene and planner with
    their 95 % intervals (Wilson for rates, t for means)."""
    scenes = list(dict.fromkeys(r["scene"] for r in summary))
    planners = list(dict.fromkeys(r["planner"] for r in summary))
    fig, axes = plt.subplots(2, 3, figsize=(14, 6.5), layout="constrained")
    width = 0.8 / max(len(planners), 1)
    with saved_png(fig, out_png) as out:
        for ax, (key, label) in zip(axes.flat, SUMMARY_PANELS, strict=True):
            for i, planner in enumerate(planners):
                xs, ys, err = _bars(summary, planner, scenes, key)
                ax.bar(np.array(xs) + (i - (len(planners) - 1) / 2) * width, ys, width,
                       yerr=err, capsize=2, color=colour_for(planner, i), label=planner)
            ax.set_xticks(range(len(scenes)), scenes, fontsize=8)
            ax.set_ylabel(label)
            ax.grid(axis="y", alpha=0.3)
        axes.flat[0].legend(fontsize=8)
        fig.suptitle("papf experiment crowd (offline): mean or rate per scene, 95 % intervals "
                     "over the seeds", fontsize=10)
    return out


def _bars(summary, planner: str, scenes: list, key: str):
    """x positions, heights and (2, k) error bars of one planner's bars."""
    xs, ys, lo, hi = [], [], [], []
    for j, scene in enumerate(scenes):
        row = next((r for r in summary if r["planner"] == planner and r["scene"] == scene), None)
        if row is None or row.get(key, "") == "":
            continue
        v = float(row[key])
        if key in ("reached", "collision"):
            d_lo, d_hi = v - float(row[f"{key}_lo"]), float(row[f"{key}_hi"]) - v
        else:
            ci = row.get(f"{key}_ci", "")
            d_lo = d_hi = float(ci) if ci != "" else 0.0
        xs.append(j)
        ys.append(v)
        lo.append(d_lo)
        hi.append(d_hi)
    return xs, ys, np.array([lo, hi]).reshape(2, -1)
