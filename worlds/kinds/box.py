"""``kind = "box"``: a rectangle ``size`` = (sx, sy) [m] about ``center``, turned by ``yaw``."""

from __future__ import annotations

import functools
import math

import numpy as np

from worlds.kinds.base import Kind, Outline, Solid, height_of
from worlds.obstacle import Obstacle


class Box(Kind):
    """A yawed rectangular footprint, ``height`` tall (walls too: :class:`worlds.kinds.wall.Wall`)."""

    name = "box"
    keys = ("center", "size", "yaw", "height", "motion")

    def parse(self, ctx, table: dict, where: str) -> Obstacle:
        height = height_of(ctx, table, where)
        center = ctx.vec(table, "center", (2,), f"{where}.center")
        size = ctx.vec(table, "size", (2,), f"{where}.size")
        if min(size) <= 0:
            ctx.fail(f"{where}.size", f"{size} must be positive")
        return Obstacle(self.name, "box", tuple(center), tuple(size),
                        yaw=ctx.number(table, "yaw", f"{where}.yaw", default=0.0), height=height)

    def table(self, ob: Obstacle) -> dict:
        return {"kind": "box", "center": list(ob.center), "height": ob.height,
                "size": list(ob.size), "yaw": ob.yaw}

    def distance(self, ob: Obstacle, pts: np.ndarray) -> np.ndarray:
        rel = pts[:, :2] - np.asarray(ob.center[:2])
        c, s = math.cos(ob.yaw), math.sin(ob.yaw)
        q = np.abs(np.column_stack([c * rel[:, 0] + s * rel[:, 1], -s * rel[:, 0] + c * rel[:, 1]]))
        q = q - np.array(ob.size) / 2
        return np.hypot(*np.maximum(q, 0.0).T) + np.minimum(q.max(axis=1), 0.0)

    def cast(self, ob, x, y, dx, dy, best, range_max=float("inf")):
        corners = self.corners(ob)
        for (x0, y0), (x1, y1) in zip(corners, corners[1:] + corners[:1], strict=True):
            best = segment_hits(best, x, y, dx, dy, x0, y0, x1, y1)
        return best

    def corners(self, ob: Obstacle) -> list[tuple[float, float]]:
        c, s = math.cos(ob.yaw), math.sin(ob.yaw)
        hx, hy = ob.size[0] / 2, ob.size[1] / 2
        cx, cy = ob.center[0], ob.center[1]
        return [(cx + c * dx - s * dy, cy + s * dx + c * dy)
                for dx, dy in ((-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy))]

    def bounds(self, ob: Obstacle) -> tuple[float, float, float, float]:
        xs, ys = zip(*self.corners(ob), strict=True)
        return min(xs), min(ys), max(xs), max(ys)

    def reach(self, ob: Obstacle) -> float:
        return max(ob.size)

    def footprint(self, ob: Obstacle) -> tuple[float, float]:
        return ob.size

    def body(self, p, client_id: int, ob: Obstacle) -> int:
        half = [ob.size[0] / 2, ob.size[1] / 2, ob.height / 2]
        return p.createCollisionShape(p.GEOM_BOX, halfExtents=half, physicsClientId=client_id)

    def triangles(self, ob: Obstacle):
        return prism(self.corners(ob), ob.height)

    def drawing(self, ob: Obstacle) -> Outline:
        return Outline(tuple(self.corners(ob)))

    def solids(self, ob: Obstacle) -> list[Solid]:
        return [Solid("cube", (ob.center[0], ob.center[1], ob.height / 2),
                     (ob.size[0], ob.size[1], ob.height), ob.yaw)]


def prism(outline, height: float) -> tuple[np.ndarray, np.ndarray]:
    """(vertices, faces) of a closed prism from the floor to ``height`` [m] over a convex
    counter-clockwise ``outline`` [(x, y)] (fans for the caps, two triangles per side)."""
    xy = np.asarray(outline, float)
    n = len(xy)
    verts = np.zeros((2 * n, 3))
    verts[:n, :2] = xy
    verts[n:, :2] = xy
    verts[n:, 2] = height
    return verts, _prism_faces(n)


@functools.lru_cache(maxsize=64)
def _prism_faces(n: int) -> np.ndarray:
    """The faces of :func:`prism` over an ``n``-gon (the same for every n-gon; read-only)."""
    k = np.arange(n)
    caps = [[0, i + 1, i] for i in range(1, n - 1)] + [[n, n + i, n + i + 1] for i in range(1, n - 1)]
    sides = np.vstack([np.column_stack([k, (k + 1) % n, n + (k + 1) % n]),
                       np.column_stack([k, n + (k + 1) % n, n + k])])
    faces = np.vstack([np.array(caps, int).reshape(-1, 3), sides])
    faces.flags.writeable = False
    return faces


def segment_hits(best, x, y, dx, dy, x0, y0, x1, y1):
    """``best`` lowered where rays from (x, y) along (dx, dy) cross the segment (x0, y0)-(x1, y1) [m]."""
    ex, ey = x1 - x0, y1 - y0
    den = dx * ey - dy * ex
    with np.errstate(divide="ignore", invalid="ignore"):
        t = ((x0 - x) * ey - (y0 - y) * ex) / den
        u = ((x0 - x) * dy - (y0 - y) * dx) / den
    ok = (np.abs(den) > 1e-12) & (t > 0) & (u >= 0) & (u <= 1) & (t < best)
    return np.where(ok, t, best)
