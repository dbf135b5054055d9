"""The planner's mind at the moment it acted, and traffic over time (the report's pictures).

- :func:`planner_events` — the cycles where the planner *did* something: the temporary
  goal set or moved, or one of its own debug values changed (by kind: a point added — PAPF's
  top quark —, a path added — AR-APF's virtual wall —, a scalar changed — IAPF's lane goal);
- :func:`telling_moment` — the first of those once the robot moves (None: nothing to show);
- :func:`draw_traffic` — road lines and every moving obstacle over ``[0, t_end]``: its
  track, outlines every :data:`TRAFFIC_EVERY_S` fading with time, where it was at the end;
- :func:`moment_png` — one panel per run: world, the path (solid up to the moment), the
  robot, the moving obstacles then, and the mind, zoomed to the moment; one legend under
  the panels, never over an obstacle.

Takes arrays and messages only (the caller reads the recording). Colours: the live view's.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402

from papf.plots.mind import (  # noqa: E402
    debug_handle,
    draw_footprint,
    draw_mind,
    draw_moving,
    draw_road,
    rgba,
)
from papf.plots.world import colour_for, draw_obstacle, draw_world, saved_png  # noqa: E402
from schemas.messages import PlannerState  # noqa: E402
from worlds import World  # noqa: E402

GOAL_MOVE_M = 0.10        # [m] a temporary goal that jumps further than this "moved"
MIN_HALF_M = 0.9          # [m] smallest half-width (and half-height) of a zoomed panel
NEAR_M = 1.5              # [m] obstacles this close to the robot are in its panel
TRAFFIC_EVERY_S = 2.0     # [s] between outlines of a moving obstacle
MOVING_S = 0.02           # [m/s] the robot "moves" above this speed
PANEL_W_IN = 5.2          # [in] width of one run's panel in mind.png


@dataclass(frozen=True)
class Event:
    index: int     # into the states
    t_s: float     # [s] the cycle's stamp
    what: str      # "new top quark", "temporary goal moved", …
    rank: int = 5      # lower = more telling (RANKS); 5: after every planner change


def _xy(p) -> tuple[float, float] | None:
    return (float(p[0]), float(p[1])) if len(p) >= 2 else None


def planner_events(states: Sequence[PlannerState]) -> list[Event]:
    """Every cycle where the planner changed its mind, in time order (see module doc)."""
    out, prev = [], None
    for i, s in enumerate(states):
        rank, what = _change(prev, s)
        if what:
            out.append(Event(i, s.stamp_ns / 1e9, what, rank))
        prev = s
    return out


#: what a change of each kind says and how telling it is (lower first): one of the plug-in's
#: points added, a scalar of it changed, the temporary goal (or a point of it) moved, one of
#: its paths added, the temporary goal set
RANKS = {"points": 0, "scalar": 1, "moved": 2, "paths": 3, "set": 4}


def _change(prev: PlannerState | None, s: PlannerState) -> tuple[int, str]:
    """(rank, words) of the most telling change from ``prev`` to ``s``; (0, '') for none."""
    found = [(RANKS[kind], what) for kind, what in _debug_changes(prev, s)]
    tg = _xy(s.temporary_goal)
    tg0 = _xy(prev.temporary_goal) if prev is not None else None
    if tg is not None and (tg0 is None or math.dist(tg, tg0) > GOAL_MOVE_M):
        found.append((RANKS["moved"], "temporary goal moved") if tg0 is not None else
                     (RANKS["set"], "temporary goal set"))
    return min(found) if found else (0, "")


def _debug_changes(prev: PlannerState | None, s: PlannerState):
    """(kind of change, words) of each of the plug-in's debug values that changed, by kind
    (a count changing is not an event: it changes every cycle)."""
    before = {d.name: d for d in prev.debug} if prev is not None else {}
    for d in s.debug:
        b = before.get(d.name)
        if d.kind == "points" and len(d.points) > (len(b.points) if b else 0):
            yield "points", f"new {d.caption}"
        elif d.kind == "paths" and len(d.paths) > (len(b.paths) if b else 0):
            yield "paths", f"new {d.caption}"
        elif d.kind == "scalar" and math.isfinite(d.value) and not (
                b is not None and math.isfinite(b.value) and abs(d.value - b.value) < 1e-6):
            yield "scalar", f"{d.words()}"
        elif d.kind == "point" and d.points and (
                b is None or not b.points or math.dist(d.points[0], b.points[0]) > GOAL_MOVE_M):
            yield "moved", f"{d.caption} moved"


def telling_moment(states: Sequence[PlannerState], t_moving_s: float) -> Event | None:
    """The first event of the most telling kind (:data:`RANKS`) at or after the robot's
    first motion ``t_moving_s`` [s]; None when the planner did none of them."""
    events = [e for e in planner_events(states) if e.t_s >= t_moving_s]
    return min(events, key=lambda e: (e.rank, e.t_s), default=None)


def slowest_moment(states: Sequence[PlannerState], t_moving_s: float,
                        drop: float = 0.8) -> Event | None:
    """The cycle with the lowest target speed after the first motion (IAPF's speed
    adaptation, eq. 26; APF stalling), when below ``drop`` times the highest (else None)."""
    idx = [i for i, s in enumerate(states) if s.stamp_ns / 1e9 >= t_moving_s and s.v_target > 0]
    if not idx:
        return None
    top = max(states[i].v_target for i in idx)
    low = min(idx, key=lambda i: states[i].v_target)
    if states[low].v_target >= drop * top:
        return None
    return Event(low, states[low].stamp_ns / 1e9,
                 f"slowest: target speed {states[low].v_target:.2f} m/s")


def closest_to_traffic(world: World, t: np.ndarray, xy: np.ndarray) -> tuple[int, float] | None:
    """(pose index, distance [m]) where the robot came closest to a moving obstacle's centre."""
    moving = [ob for ob in world.obstacles if ob.motion is not None]
    if not moving or not len(t):
        return None
    d = np.full(len(t), np.inf)
    for ob in moving:
        centres = np.array([ob.at(float(ti)).center[:2] for ti in t])
        d = np.minimum(d, np.hypot(*(centres - xy).T))
    k = int(np.argmin(d))
    return k, float(d[k])


def first_motion_s(t: np.ndarray, v: np.ndarray) -> float:
    """[s] first time the speed exceeds :data:`MOVING_S` (the last time if never)."""
    moving = np.flatnonzero(np.abs(v) > MOVING_S)
    return float(t[moving[0]]) if moving.size else (float(t[-1]) if len(t) else 0.0)


def static_world(world: World) -> World:
    """``world`` without its moving obstacles (they are drawn where they are at a time)."""
    return replace(world, obstacles=tuple(ob for ob in world.obstacles if ob.motion is None))


def draw_traffic(ax, world: World, t_end_s: float) -> list:
    """Road lines, and each moving obstacle's track and outlines over ``[0, t_end_s]``."""
    out = draw_road(ax, world)
    times = np.arange(0.0, max(t_end_s, 0.0) + 1e-9, TRAFFIC_EVERY_S)
    movers = [ob for ob in world.obstacles if ob.motion is not None]
    for n, ob in enumerate(movers):
        track = np.array([ob.at(float(t)).center[:2] for t in np.linspace(0, t_end_s, 60)])
        label = (f"moving obstacle: track, every {TRAFFIC_EVERY_S:g} s (darker: later), "
                 f"at {t_end_s:.1f} s" if n == 0 else None)
        out += ax.plot(track[:, 0], track[:, 1], color=rgba("moving", 0.9), lw=0.8, ls=":",
                       zorder=3, label=label)
        for k, t in enumerate(times):
            alpha = 0.15 + 0.45 * k / max(len(times) - 1, 1)
            out.append(_outline(ax, ob.at(float(t)), alpha))
        out += draw_moving(ax, world, t_end_s)
    return out


def _outline(ax, here, alpha: float):
    return draw_obstacle(ax, here, color=rgba("moving", alpha), zorder=3, fill=False, lw=0.8)


@dataclass
class MomentPanel:
    """One run's picture: its path, the planner's states and the label."""

    label: str                  # "papf seed 0 (reached)"
    planner: str
    t: np.ndarray               # [s] pose times
    xyyaw: np.ndarray           # (n, 3) [m, m, rad]
    v: np.ndarray               # [m/s] at the pose times (for the first motion)
    states: list[PlannerState]


@dataclass(frozen=True)
class View:
    """What a panel shows: the moment (None: the whole path), its pose index, the window."""

    event: Event | None
    k: int                       # index of the pose at the moment
    mid: tuple[float, float]     # [m] centre of the window
    half: tuple[float, float]    # [m] half-width, half-height


def _window(points: np.ndarray, centre: np.ndarray, world: World | None
            ) -> tuple[tuple[float, float], tuple[float, float]]:
    """Centre and half-sizes [m] of a view on ``centre`` holding ``points`` (on a road: its
    lines too), at least :data:`MIN_HALF_M` across and at most 2:1 either way."""
    pts = np.vstack([points, centre[None, :]]) if len(points) else centre[None, :]
    if world is not None:   # the static obstacles near the robot: what it reacts to
        near = [ob.center[:2] for ob in world.obstacles if ob.motion is None
                and math.dist(ob.center[:2], centre) < NEAR_M]
        pts = np.vstack([pts, near]) if near else pts
    if world is not None and world.road is not None:
        ys = [y for y in _road_ys(world) if abs(y - centre[1]) < 3 * MIN_HALF_M]
        pts = np.vstack([pts, [[centre[0], y] for y in ys]]) if ys else pts
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    mid = 0.5 * (lo + hi)
    hx, hy = (max(MIN_HALF_M, 0.5 * float(e) + 0.4) for e in hi - lo)
    hx, hy = max(hx, hy / 2), max(hy, hx / 2)
    return (float(mid[0]), float(mid[1])), (hx, hy)


def _road_ys(world: World) -> list[float]:
    """[m] y of the road's painted lines."""
    return [float(line.y) for line in world.road.lines()]


def _mind_points(s: PlannerState) -> np.ndarray:
    parts = [np.asarray(s.predicted_path, float).reshape(-1, 2),
             *(np.asarray(d.points, float).reshape(-1, 2) for d in s.debug)]
    if len(s.temporary_goal) >= 2:
        parts.append(np.asarray(s.temporary_goal[:2], float).reshape(1, 2))
    return np.vstack(parts)


def choose_view(p: MomentPanel, world: World | None) -> View:
    """The moment of ``p`` (what the planner did; else its slowest cycle; else the closest
    approach to traffic) and the window around it."""
    moving_s = first_motion_s(p.t, p.v)
    event = telling_moment(p.states, moving_s) or slowest_moment(p.states, moving_s)
    near = closest_to_traffic(world, p.t, p.xyyaw[:, :2]) if world is not None else None
    if event is None and near is not None:
        i = max(int(np.searchsorted([s.stamp_ns / 1e9 for s in p.states], p.t[near[0]],
                                    side="right")) - 1, 0)
        event = Event(i, float(p.t[near[0]]), f"closest to a moving obstacle ({near[1]:.2f} m)")
    if event is not None and not p.states:
        event = None
    t_m = event.t_s if event else float(p.t[-1])
    k = max(int(np.searchsorted(p.t, t_m, side="right")) - 1, 0)
    xy = p.xyyaw[:, :2]
    if event is None:   # the whole path
        mid, half = _window(xy, xy[k], None)
    else:
        mid, half = _window(_mind_points(p.states[event.index]), xy[k], world)
    return View(event, k, mid, half)


def _draw_panel(ax, p: MomentPanel, world: World | None, view: View) -> str:
    """Draw one panel at ``view``; returns what the planner did then ("" for none)."""
    colour = colour_for(p.planner, 0)
    event, k = view.event, view.k
    t_m = event.t_s if event else float(p.t[-1])
    if world is not None and world.dims == 2:
        draw_world(ax, static_world(world))
        draw_road(ax, world)
        _tracks(ax, world, float(p.t[-1]) if len(p.t) else 0.0)
        draw_moving(ax, world, t_m)
    xy = p.xyyaw[:, :2]
    ax.plot(xy[:, 0], xy[:, 1], color=colour, lw=1.0, alpha=0.35, zorder=3)
    ax.plot(xy[: k + 1, 0], xy[: k + 1, 1], color=colour, lw=1.8, zorder=3)
    draw_footprint(ax, *p.xyyaw[k])
    (mx, my), (hx, hy) = view.mid, view.half
    ax.set_xlim(mx - hx, mx + hx)
    ax.set_ylim(my - hy, my + hy)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    if event is None:
        ax.set_title(f"{p.label}\nno prediction to show: the whole path", fontsize=9)
        return ""
    draw_mind(ax, p.states[event.index], labels=False)
    ax.set_title(f"{p.label}\nt = {event.t_s:.1f} s: {event.what}", fontsize=9)
    return event.what


def _tracks(ax, world: World, t_end_s: float) -> None:
    """Each moving obstacle's track over the run, dotted (where it came from and goes)."""
    for ob in world.obstacles:
        if ob.motion is not None:
            track = np.array([ob.at(float(t)).center[:2] for t in np.linspace(0, t_end_s, 80)])
            ax.plot(track[:, 0], track[:, 1], color=rgba("moving", 0.9), lw=0.9, ls=":",
                    zorder=3)


def _legend_handles(world: World | None, debug=()) -> list:
    """The legend: what every panel shows, and the planners' own debug values drawn
    (``debug``: one of each name, in their declared style)."""
    handles = [Line2D([], [], color="0.3", lw=1.8, label="path so far (faint: after)"),
               Patch(facecolor=rgba("robot"), edgecolor=rgba("robot", 1.0), label="robot then"),
               Line2D([], [], color=rgba("prediction"), lw=2.0, label="prediction"),
               *(h for h in map(debug_handle, debug) if h is not None),
               Line2D([], [], marker="D", ls="", color=rgba("temporary_goal"), mec="k",
                      label="temporary goal"),
               Patch(color="0.35", label="obstacle")]
    if world is not None and any(ob.motion is not None for ob in world.obstacles):
        handles.append(Patch(color=rgba("moving"), label="moving obstacle then"))
        handles.append(Line2D([], [], color=rgba("moving", 0.9), lw=0.9, ls=":",
                              label="its track over the run"))
    if world is not None and world.road is not None:
        handles.append(Line2D([], [], color=rgba("road"), lw=1.5, label="road lines"))
    return handles


def moment_png(panels: Sequence[MomentPanel], world: World | None, out_png: str | Path) -> Path:
    """The report's ``mind.png`` (see module doc): one panel per run in ``panels``, each as
    wide as :data:`PANEL_W_IN` and as tall as the tallest window needs."""
    n = max(len(panels), 1)
    views = [choose_view(p, world) for p in panels]
    ratio = max([v.half[1] / v.half[0] for v in views] or [1.0])
    height = PANEL_W_IN * ratio + 1.6   # + the two-line title, x label and the legend
    fig, axes = plt.subplots(1, n, figsize=(PANEL_W_IN * n + 0.6, height), squeeze=False,
                             layout="constrained")
    with saved_png(fig, out_png) as out:
        for ax, p, v in zip(axes[0], panels, views, strict=False):
            _draw_panel(ax, p, world, v)
        drawn = {d.name: d for p, v in zip(panels, views, strict=False) if v.event is not None
                 and p.states for d in p.states[v.event.index].debug}
        fig.legend(handles=_legend_handles(world, tuple(drawn.values())), loc="outside lower center",
                   ncol=min(4, 2 + n), fontsize=8, frameon=False)
    return out
