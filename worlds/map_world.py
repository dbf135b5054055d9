"""A bare map YAML as a world: ``papf run --world lab.yaml --start=X,Y[,YAW] --goal=X,Y``.

:func:`map_world_file` writes the world TOML of such a run (``[robot]``, ``[goal]``,
``[map] file`` = the YAML) in a fresh temporary folder — never beside the user's files —
so every node loads it like any world; :func:`parse_point` reads ``--start``/``--goal``.
Used by ``papf run``, ``papf plan`` (papf/cli/options.py).
"""

from __future__ import annotations

import json
import math
import tempfile
from pathlib import Path

from common.errors import WorldError
from worlds import load_world
from worlds.maps import load_map

MAP_SUFFIXES = (".yaml", ".yml")


def is_map(name_or_path: str) -> bool:
    """True when ``--world`` names a map YAML rather than a world."""
    return Path(name_or_path).suffix.lower() in MAP_SUFFIXES


def parse_point(text: str, option: str, lengths: tuple[int, ...]) -> list[float]:
    """``X,Y[,YAW]`` -> floats; WorldError naming ``option`` and the expected form."""
    parts = text.split(",")
    try:
        vals = [float(v) for v in parts]
    except ValueError:
        vals = []
    if len(vals) not in lengths or not all(math.isfinite(v) for v in vals):
        form = "X,Y[,YAW]" if 3 in lengths else "X,Y"
        raise WorldError(f"{option} {text!r}: give {form} in metres (and radians), e.g. "
                         f"{option}=-1.5,2" + (",0.5" if 3 in lengths else ""))
    return vals


def map_world_file(yaml_path: str, start: str | None, goal: str | None,
                   tolerance: float = 0.1) -> str:
    """The path of a world TOML running the map ``yaml_path`` from ``start`` to ``goal``."""
    if start is None or goal is None:
        raise WorldError(f"--world {yaml_path!r} is a map: give --start=X,Y[,YAW] and "
                         "--goal=X,Y too")
    path = Path(yaml_path)
    if not path.is_file():
        raise WorldError(f"map file {yaml_path!r} does not exist")
    load_map(path)                                   # a bad map: one line, nothing written
    s = parse_point(start, "--start", (2, 3))
    g = parse_point(goal, "--goal", (2,))
    text = (f"name = {json.dumps(path.stem)}\n"
            f"description = {json.dumps(f'the map {path.name}, start and goal from the command line')}\n"
            f"[robot]\nstart = {s!r}\n[goal]\nposition = {g!r}\ntolerance = {tolerance!r}\n"
            f"[map]\nfile = {json.dumps(str(path.resolve()))}\n")
    out = Path(tempfile.mkdtemp(prefix="papf-map-")) / f"{path.stem}.toml"
    out.write_text(text, encoding="utf-8")
    load_world(out)                                  # start/goal bounds: one line
    return str(out)


def world_map(world: str | None, resolution: float = 0.05):
    """What ROS 2 tools get as ``/map`` for ``world`` (a name or file): a map world's own map,
    else its obstacles at t = 0 rasterised (:func:`rasterize`); None without a world or for a
    3-D one. WorldError (one line) when the world does not load."""
    if not world:
        return None
    from worlds import load_world

    w = load_world(world)
    if w.dims != 2:
        return None
    grids = [ob.grid for ob in w.obstacles if hasattr(ob, "grid")]
    return grids[0] if len(grids) == 1 and len(w.obstacles) == 1 else rasterize(w, resolution)


def rasterize(world, resolution: float = 0.05, margin_m: float = 1.0):
    """The world's obstacles (at t = 0) as an :class:`~worlds.maps.OccupancyMap` [m/cell]:
    a cell is occupied when an obstacle reaches within half its diagonal of its centre;
    the grid covers start, goal and every obstacle plus ``margin_m`` [m]."""
    import numpy as np

    from worlds.maps import FREE, OCCUPIED, OccupancyMap

    obstacles = world.obstacles_at(0.0)
    boxes = [ob.model.bounds(ob) for ob in obstacles]
    xs = [world.start[0], world.goal[0], *(b[0] for b in boxes), *(b[2] for b in boxes)]
    ys = [world.start[1], world.goal[1], *(b[1] for b in boxes), *(b[3] for b in boxes)]
    x0, y0 = min(xs) - margin_m, min(ys) - margin_m
    cols = int(math.ceil((max(xs) + margin_m - x0) / resolution))
    rows = int(math.ceil((max(ys) + margin_m - y0) / resolution))
    data = np.full((rows, cols), FREE, np.int8)
    reach = resolution * math.sqrt(0.5)
    for ob, (bx0, by0, bx1, by1) in zip(obstacles, boxes, strict=True):
        c0, c1 = max(int((bx0 - x0) / resolution) - 1, 0), min(int((bx1 - x0) / resolution) + 2, cols)
        r0, r1 = max(int((by0 - y0) / resolution) - 1, 0), min(int((by1 - y0) / resolution) + 2, rows)
        if c0 >= c1 or r0 >= r1:
            continue
        cx, cy = np.meshgrid(x0 + (np.arange(c0, c1) + 0.5) * resolution,
                             y0 + (np.arange(r0, r1) + 0.5) * resolution)
        d = ob.model.distance(ob, np.column_stack([cx.ravel(), cy.ravel()]))
        hit = (d <= reach).reshape(cy.shape)
        data[r0:r1, c0:c1][hit] = OCCUPIED
    return OccupancyMap(data, resolution, (x0, y0, 0.0), source=world.source)
