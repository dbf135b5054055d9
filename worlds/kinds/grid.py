"""``[map]``: a ROS occupancy map (:mod:`worlds.maps`) as one obstacle — its walls are the
occupied and unknown cells. ``[map] file`` (relative to the world file), ``height`` [m].

Geometry: rays march the grid cell by cell (Amanatides & Woo's traversal, all rays at
once), only as far as ``range_max``; distances come from a k-d tree of wall cells. The
physics body: wall cells merged into rectangles (greedy run-length merge: runs of a row,
extended while the next row has the same run) as one static compound of boxes.
"""

from __future__ import annotations

import math
from functools import lru_cache
from pathlib import Path

import numpy as np

from worlds.kinds.base import Kind, Raster, Solid, height_of
from worlds.maps import OccupancyMap, load_map
from worlds.obstacle import Obstacle


class Grid(Kind):
    """The walls of an occupancy map, ``height`` tall, in the map's frame (origin, yaw)."""

    name = "map"
    keys = ("file", "height")
    listed = False
    trackable = False
    movable = False

    def parse(self, ctx, table: dict, where: str) -> Obstacle:
        if not isinstance(table, dict):
            ctx.fail(where, "must be a table with file = \"map.yaml\" (and height [m])")
        file = ctx.str(table, "file", f"{where}.file")
        height = height_of(ctx, table, where)
        path = Path(file)
        if not path.is_absolute() and ctx.source not in ("", "<dict>"):
            path = Path(ctx.source).parent / path
        return from_map(load_map(path), height)

    def table(self, ob: Obstacle) -> dict:
        return {"file": ob.grid.source, "height": ob.height}

    def distance(self, ob: Obstacle, pts: np.ndarray) -> np.ndarray:
        """To the nearest wall cell [m], within half a cell's diagonal (< 0: in a wall cell)."""
        grid: OccupancyMap = ob.grid
        tree = _wall_tree(grid)
        if tree is None:
            return np.full(len(pts), np.inf)
        cells = grid.to_cells(np.asarray(pts, float)[:, :2])
        d, _ = tree.query(cells)
        inside = _wall_at(grid, np.floor(cells).astype(np.int64))
        return np.where(inside, -0.5, d - 0.5) * grid.resolution

    def cast(self, ob, x, y, dx, dy, best, range_max=math.inf):
        grid: OccupancyMap = ob.grid
        c, s = math.cos(grid.origin[2]), math.sin(grid.origin[2])
        start = grid.to_cells(np.array([[x, y]]))[0]
        du, dv = c * dx + s * dy, -s * dx + c * dy
        t = march(grid.walls, start[0], start[1], np.broadcast_to(du, np.shape(best)).ravel(),
                  np.broadcast_to(dv, np.shape(best)).ravel(), range_max / grid.resolution)
        t = t.reshape(np.shape(best)) * grid.resolution
        return np.where(t < best, t, best)

    def bounds(self, ob: Obstacle) -> tuple[float, float, float, float]:
        grid: OccupancyMap = ob.grid
        rows, cols = grid.shape
        pts = grid.to_world(np.array([[0, 0], [cols, 0], [cols, rows], [0, rows]], float))
        return (*pts.min(axis=0), *pts.max(axis=0))

    def reach(self, ob: Obstacle) -> float:
        return math.hypot(*ob.grid.shape) * ob.grid.resolution

    def footprint(self, ob: Obstacle) -> tuple[float, float]:
        rows, cols = ob.grid.shape
        return cols * ob.grid.resolution, rows * ob.grid.resolution

    def bodies(self, p, client_id: int, ob: Obstacle) -> list[int]:
        """The merged rectangles as static triangle meshes (BVH: a ray or a contact test
        visits only nearby triangles), :data:`MESH_BOXES` rectangles each. Not a compound
        of boxes: pybullet keeps only the first 16 shapes of a compound, silently."""
        boxes = wall_boxes(ob.grid)
        return [p.createCollisionShape(p.GEOM_MESH, vertices=v, indices=i,
                                       physicsClientId=client_id)
                for v, i in box_meshes(boxes, ob.height)]

    def pose(self, p, ob: Obstacle) -> tuple[list[float], list[float]]:
        """The map's origin on the floor, turned by its yaw (mesh vertices in its frame)."""
        quat = p.getQuaternionFromEuler([0.0, 0.0, ob.yaw])
        return [ob.center[0], ob.center[1], 0.0], list(quat)

    def drawing(self, ob: Obstacle) -> Raster:
        g: OccupancyMap = ob.grid
        return Raster(g.walls, (g.origin[0], g.origin[1]), g.origin[2], g.resolution)

    def solids(self, ob: Obstacle) -> list[Solid]:
        boxes = wall_boxes(ob.grid)
        yaw = ob.grid.origin[2]
        c, s = math.cos(yaw), math.sin(yaw)
        x0, y0 = ob.center[0], ob.center[1]
        return [Solid("cube", (x0 + c * u - s * v, y0 + s * u + c * v, ob.height / 2),
                      (w, h, ob.height), yaw) for u, v, w, h in boxes.tolist()]


MESH_BOXES = 4096   # [-] rectangles per pybullet mesh (32,768 vertices)
_CORNERS = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0],
                     [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], float)
_FACES = np.array([[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
                   [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]])


def box_meshes(boxes: np.ndarray, height: float):
    """(vertices, indices) lists per chunk of :data:`MESH_BOXES` rectangles (u, v, w, h) [m]:
    each a closed box from the floor to ``height`` [m], in the map's frame."""
    for k in range(0, len(boxes), MESH_BOXES):
        b = boxes[k:k + MESH_BOXES]
        xy = b[:, None, 0:2] + _CORNERS[None, :, 0:2] * b[:, None, 2:4] / 2
        z = np.broadcast_to(_CORNERS[None, :, 2:] * height, (len(b), 8, 1))
        verts = np.concatenate([xy, z], axis=2).reshape(-1, 3)
        idx = (_FACES[None] + 8 * np.arange(len(b))[:, None, None]).reshape(-1)
        yield verts.tolist(), idx.tolist()


def from_map(grid: OccupancyMap, height: float) -> Obstacle:
    """The obstacle of an occupancy map: centre = the map's origin, yaw = its yaw."""
    return Obstacle("map", "grid", (grid.origin[0], grid.origin[1]), yaw=grid.origin[2],
                    height=height, grid=grid)


def march(walls: np.ndarray, u: float, v: float, du: np.ndarray, dv: np.ndarray,
          limit: float) -> np.ndarray:
    """Distance [cells] along unit directions (du, dv) from (u, v) [cells] to the first wall
    cell (inf: none within ``limit`` cells); a wall cell the ray starts in is not a hit."""
    rows, cols = walls.shape
    n = len(du)
    ix = np.full(n, math.floor(u), np.int64)
    iy = np.full(n, math.floor(v), np.int64)
    sx, sy = np.where(du > 0, 1, -1), np.where(dv > 0, 1, -1)
    with np.errstate(divide="ignore", invalid="ignore"):
        ddx, ddy = np.abs(1.0 / du), np.abs(1.0 / dv)
        nx = np.where(du > 0, ix + 1 - u, u - ix) * ddx
        ny = np.where(dv > 0, iy + 1 - v, v - iy) * ddy
    nx, ny = np.where(du == 0, np.inf, nx), np.where(dv == 0, np.inf, ny)
    out = np.full(n, np.inf)
    live = np.arange(n)
    while live.size:
        step_x = nx[live] < ny[live]
        t = np.where(step_x, nx[live], ny[live])
        ix[live] += np.where(step_x, sx[live], 0)
        iy[live] += np.where(step_x, 0, sy[live])
        nx[live] += np.where(step_x, ddx[live], 0.0)
        ny[live] += np.where(step_x, 0.0, ddy[live])
        a, b = ix[live], iy[live]
        inside = (a >= 0) & (a < cols) & (b >= 0) & (b < rows)
        hit = np.zeros(live.size, bool)
        hit[inside] = walls[b[inside], a[inside]]
        out[live[hit]] = t[hit]
        live = live[~hit & (t <= limit) & _may_enter(a, b, sx[live], sy[live], cols, rows)]
    return np.where(out <= limit, out, np.inf)


def _may_enter(a, b, sx, sy, cols, rows):
    """False for a ray outside the grid and moving away from it."""
    return ~(((a < 0) & (sx < 0)) | ((a >= cols) & (sx > 0))
             | ((b < 0) & (sy < 0)) | ((b >= rows) & (sy > 0)))


def _wall_at(grid: OccupancyMap, idx: np.ndarray) -> np.ndarray:
    rows, cols = grid.shape
    ok = (idx[:, 0] >= 0) & (idx[:, 0] < cols) & (idx[:, 1] >= 0) & (idx[:, 1] < rows)
    out = np.zeros(len(idx), bool)
    out[ok] = grid.walls[idx[ok, 1], idx[ok, 0]]
    return out


@lru_cache(maxsize=4)
def _wall_tree(grid: OccupancyMap):
    from scipy.spatial import cKDTree

    rows, cols = np.nonzero(grid.walls)
    if not rows.size:
        return None
    return cKDTree(np.column_stack([cols + 0.5, rows + 0.5]))


@lru_cache(maxsize=4)
def wall_boxes(grid: OccupancyMap) -> np.ndarray:
    """(K, 4) rectangles (u, v centre, width, height) [m, map frame] covering every wall
    cell exactly once: a greedy run-length merge of the rows (module doc)."""
    walls = grid.walls
    rows = walls.shape[0]
    open_runs: dict[tuple[int, int], int] = {}
    rects = []
    pad = np.zeros((rows, 1), bool)
    edges = np.diff(np.hstack([pad, walls, pad]).astype(np.int8), axis=1)
    for r in range(rows + 1):
        runs = set()
        if r < rows:
            starts, = np.nonzero(edges[r] == 1)
            ends, = np.nonzero(edges[r] == -1)
            runs = set(zip(starts.tolist(), ends.tolist(), strict=True))
        for key in [k for k in open_runs if k not in runs]:
            rects.append((key[0], open_runs.pop(key), key[1], r))
        for key in runs:
            open_runs.setdefault(key, r)
    res = grid.resolution
    a = np.array(rects, float).reshape(-1, 4)
    return np.column_stack([(a[:, 0] + a[:, 2]) / 2 * res, (a[:, 1] + a[:, 3]) / 2 * res,
                            (a[:, 2] - a[:, 0]) * res, (a[:, 3] - a[:, 1]) * res])
