"""Figures of the IAPF cases like the paper's Figs. 10-13, drawn from the experiment's CSVs.

Top: the road (solid and broken lines) and the host's path per planner; at time marks the
host (IAPF) and every vehicle as footprints labelled with the time; the temporary lane
goal where it was active. Bottom: speed over time (host per planner, vehicles dotted).
"""

from __future__ import annotations

import csv
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.patches import Polygon  # noqa: E402

from nodes.planner.registry import car_variants  # noqa: E402
from papf.plots.world import saved_png  # noqa: E402
from worlds import World, load_world  # noqa: E402
from worlds.shapes import rect_corners  # noqa: E402

COLOURS = {variant: v[3] for variant, v in car_variants().items()}
PROPOSED = next(iter(car_variants()))   # the car planner itself (IAPF): drawn on top, with its boxes
MARK_EVERY_S = 1.0
HOST_SIZE = (4.5, 1.8)


def _read(path: Path) -> list[dict]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def _marks(rows: list[dict], every: float) -> list[dict]:
    return [r for r in rows if abs(float(r["t"]) / every - round(float(r["t"]) / every)) < 1e-6]


def _road(ax, world: World, x0: float, x1: float) -> None:
    road = world.road
    for i in range(road.lanes + 1):
        y = road.y_min + i * road.lane_width
        solid = i in (0, road.lanes)
        ax.plot([x0, x1], [y, y], color="black", lw=1.5 if solid else 1.0,
                ls="-" if solid else (0, (6, 6)))


def _box(ax, x, y, yaw, size, colour, label=None, alpha=0.35) -> None:
    ax.add_patch(Polygon(rect_corners(x, y, yaw, *size), closed=True, fc=colour, ec=colour,
                         alpha=alpha))
    if label:
        ax.text(x, y + size[1] / 2 + 0.15, label, ha="center", va="bottom", fontsize=6, color=colour)


def plot_case(out_png: str | Path, case: str, csv_dir: str | Path, labels: dict[str, str]) -> Path:
    """One case's figure from ``csv_dir``/``<case>-<planner>.csv`` and ``<case>-vehicles.csv``,
    for each planner of ``labels`` (planner -> its legend label) whose CSV is there."""
    csv_dir = Path(csv_dir)
    world = load_world(case)
    runs = {pl: _read(csv_dir / f"{case}-{pl}.csv") for pl in labels
            if (csv_dir / f"{case}-{pl}.csv").exists()}
    vehicles = _read(csv_dir / f"{case}-vehicles.csv")
    xs = [float(r["x"]) for rows in runs.values() for r in rows] + [float(r["x"]) for r in vehicles]
    fig, (ax, av) = plt.subplots(2, 1, figsize=(11, 6.2), gridspec_kw={"height_ratios": [1.5, 1]})
    with saved_png(fig, out_png) as out:
        x0, x1 = min(xs) - 5, max(xs) + 5
        _road(ax, world, x0, x1)
        for pl, rows in runs.items():
            ax.plot([float(r["x"]) for r in rows], [float(r["y"]) for r in rows],
                    color=COLOURS[pl], lw=1.2, label=labels[pl])
        every = MARK_EVERY_S if float(vehicles[-1]["t"]) <= 6.0 else 2.0 * MARK_EVERY_S
        for r in _marks(runs.get(PROPOSED, []), every):
            _box(ax, float(r["x"]), float(r["y"]), float(r["yaw"]), HOST_SIZE, COLOURS[PROPOSED],
                 f"{float(r['t']):g}s")
        for r in _marks(vehicles, every):
            _box(ax, float(r["x"]), float(r["y"]), float(r["yaw"]),
                 (float(r["length"]), float(r["width"])), "dimgray", f"{float(r['t']):g}s", 0.25)
        goal = [(float(r["x"]), float(r["temp_goal_y"])) for r in runs.get(PROPOSED, [])
                if r["temp_goal_y"]]
        if goal:
            ax.scatter(*zip(*goal, strict=True), s=4, color="tab:orange",
                       label="temporary lane goal (y, at the host's x)")
        y_max = world.road.y_min + world.road.lanes * world.road.lane_width
        ax.set_xlim(x0, x1)
        ax.set_ylim(world.road.y_min - 1.0, y_max + 1.0)
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.set_title(f"{case}: host (IAPF, blue) and vehicles (grey) every {every:g} s")
        ax.legend(loc="upper left", fontsize=7, ncol=4)
        for pl, rows in sorted(runs.items(), key=lambda kv: kv[0] == PROPOSED):   # IAPF on top
            av.plot([float(r["t"]) for r in rows], [3.6 * float(r["v"]) for r in rows],
                    color=COLOURS[pl], label=labels[pl], lw=2.0 if pl == PROPOSED else 1.2)
        ids = sorted({r["id"] for r in vehicles})
        for i in ids:
            rows = [r for r in vehicles if r["id"] == i]
            av.plot([float(r["t"]) for r in rows], [3.6 * float(r["v"]) for r in rows],
                    color="dimgray", ls=":", lw=1)
        av.set_xlabel("t [s]")
        av.set_ylabel("speed [km/h] (vehicles dotted)")
        av.grid(alpha=0.3)
        av.legend(loc="lower right", fontsize=7)
        fig.tight_layout()
    return out

