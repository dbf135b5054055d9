"""``kind = "sphere"``: a ball of ``radius`` [m] about ``center`` (x, y, z) — Wang's 3-D worlds."""

from __future__ import annotations

import numpy as np

from worlds.kinds.base import Disc, Solid, height_of
from worlds.kinds.cylinder import Cylinder
from worlds.obstacle import Obstacle


class Sphere(Cylinder):
    """A ball; in the plane (top views, 2-D rays) its footprint is its equator's disc."""

    name = "sphere"
    keys = ("center", "radius", "height", "motion")   # motion: the parser refuses it
    world_dims = (3,)
    movable = False

    def parse(self, ctx, table: dict, where: str) -> Obstacle:
        height = height_of(ctx, table, where)
        center = ctx.vec(table, "center", (3,), f"{where}.center")
        return Obstacle(self.name, "sphere", tuple(center),
                        radius=ctx.positive(table, "radius", f"{where}.radius"), height=height)

    def distance(self, ob: Obstacle, pts: np.ndarray) -> np.ndarray:
        """3-D distance for (N, 3) points, the footprint's for (N, 2)."""
        d = min(pts.shape[1], len(ob.center))
        rel = pts[:, :d] - np.asarray(ob.center[:d])
        return np.sqrt(np.sum(rel * rel, axis=1)) - ob.radius

    def pose(self, p, ob: Obstacle) -> tuple[list[float], list[float]]:
        z = ob.center[2] if len(ob.center) > 2 else ob.radius
        return [ob.center[0], ob.center[1], z], [0.0, 0.0, 0.0, 1.0]

    def body(self, p, client_id: int, ob: Obstacle) -> int:
        return p.createCollisionShape(p.GEOM_SPHERE, radius=ob.radius, physicsClientId=client_id)

    def triangles(self, ob: Obstacle):
        return None     # 3-D worlds: a few spheres, each its own body

    def drawing(self, ob: Obstacle) -> Disc:
        return Disc((ob.center[0], ob.center[1]), ob.radius)

    def solids(self, ob: Obstacle) -> list[Solid]:
        z = ob.center[2] if len(ob.center) > 2 else ob.radius
        return [Solid("sphere", (ob.center[0], ob.center[1], z), (2 * ob.radius,) * 3)]
