"""``kind = "wall"``: from ``from`` to ``to`` (x, y) [m], ``thickness`` [m] — a box along the segment."""

from __future__ import annotations

import math

from worlds.kinds.base import height_of
from worlds.kinds.box import Box
from worlds.obstacle import Obstacle

THICKNESS_M = 0.05   # [m] a wall's thickness when the file gives none (docs/worlds.md)


class Wall(Box):
    """A wall is parsed into a box (centre, (length, thickness), yaw) and is one from then on."""

    name = "wall"
    keys = ("from", "to", "thickness", "height", "motion", "yaw")

    def parse(self, ctx, table: dict, where: str) -> Obstacle:
        height = height_of(ctx, table, where)
        a = ctx.vec(table, "from", (2,), f"{where}.from")
        b = ctx.vec(table, "to", (2,), f"{where}.to")
        thickness = ctx.positive(table, "thickness", f"{where}.thickness", default=THICKNESS_M)
        length = math.dist(a, b)
        if length <= 0:
            ctx.fail(where, "wall 'from' and 'to' are the same point")
        return Obstacle(self.name, "box", ((a[0] + b[0]) / 2, (a[1] + b[1]) / 2),
                        (length, thickness), yaw=math.atan2(b[1] - a[1], b[0] - a[0]),
                        height=height)


def segment_wall(x0: float, y0: float, x1: float, y1: float) -> Obstacle:
    """A zero-thickness wall from (x0, y0) to (x1, y1) [m] (a box of no width)."""
    return Obstacle("wall", "box", ((x0 + x1) / 2, (y0 + y1) / 2),
                    (math.hypot(x1 - x0, y1 - y0), 0.0), yaw=math.atan2(y1 - y0, x1 - x0))
