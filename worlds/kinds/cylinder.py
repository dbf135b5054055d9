"""``kind = "cylinder"``: a vertical cylinder of ``radius`` [m] about ``center`` (x, y)."""

from __future__ import annotations

import math

import numpy as np

from worlds.kinds.base import Disc, Kind, Solid, height_of
from worlds.kinds.box import prism
from worlds.obstacle import Obstacle

SIDES = 16   # [-] sides of the prism a merged cylinder becomes (worlds/bullet.py)


class Cylinder(Kind):
    """A disc footprint, ``height`` tall."""

    name = "cylinder"
    keys = ("center", "radius", "height", "motion", "yaw")
    round = True

    def parse(self, ctx, table: dict, where: str) -> Obstacle:
        height = height_of(ctx, table, where)
        center = ctx.vec(table, "center", (2,), f"{where}.center")
        return Obstacle(self.name, "cylinder", tuple(center),
                        radius=ctx.positive(table, "radius", f"{where}.radius"), height=height)

    def table(self, ob: Obstacle) -> dict:
        return {"kind": self.name, "center": list(ob.center), "height": ob.height,
                "radius": ob.radius}

    def distance(self, ob: Obstacle, pts: np.ndarray) -> np.ndarray:
        rel = pts[:, :2] - np.asarray(ob.center[:2])
        return np.hypot(rel[:, 0], rel[:, 1]) - ob.radius

    def cast(self, ob, x, y, dx, dy, best, range_max=float("inf")):
        return circle_hits(best, x, y, dx, dy, ob.center[0], ob.center[1], ob.radius)

    def bounds(self, ob: Obstacle) -> tuple[float, float, float, float]:
        cx, cy, r = ob.center[0], ob.center[1], ob.radius
        return cx - r, cy - r, cx + r, cy + r

    def reach(self, ob: Obstacle) -> float:
        return ob.radius

    def footprint(self, ob: Obstacle) -> tuple[float, float]:
        return 2 * ob.radius, 2 * ob.radius

    def body(self, p, client_id: int, ob: Obstacle) -> int:
        return p.createCollisionShape(p.GEOM_CYLINDER, radius=ob.radius, height=ob.height,
                                      physicsClientId=client_id)

    def triangles(self, ob: Obstacle):
        """A :data:`SIDES`-gon prism around the cylinder (circumscribed: never smaller)."""
        r = ob.radius / math.cos(math.pi / SIDES)
        a = np.arange(SIDES) * (2 * math.pi / SIDES)
        return prism(np.column_stack([ob.center[0] + r * np.cos(a), ob.center[1] + r * np.sin(a)]),
                     ob.height)

    def drawing(self, ob: Obstacle) -> Disc:
        return Disc((ob.center[0], ob.center[1]), ob.radius)

    def solids(self, ob: Obstacle) -> list[Solid]:
        return [Solid("cylinder", (ob.center[0], ob.center[1], ob.height / 2),
                     (2 * ob.radius, 2 * ob.radius, ob.height))]


def circle_hits(best, x, y, dx, dy, cx, cy, r):
    """``best`` lowered where rays from (x, y) along (dx, dy) enter the circle (cx, cy, r) [m]."""
    ox, oy = x - cx, y - cy
    b = ox * dx + oy * dy
    disc = b * b - (ox * ox + oy * oy - r ** 2)
    with np.errstate(invalid="ignore"):
        t = -b - np.sqrt(disc)
    return np.where((disc >= 0) & (t > 0) & (t < best), t, best)


