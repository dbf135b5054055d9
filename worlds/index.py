"""Which static obstacles are near a point, without walking all of them: a uniform grid of
bounding boxes (used by the world simulator to name the obstacle a robot touches inside a
merged mesh, and by anything else that asks "what is here" in a world of thousands).

Each static obstacle is filed in every cell of :data:`CELL_M` its bounding box overlaps; a
query looks at the cells within its radius and measures only the obstacles filed there, so
its cost depends on what is near, not on the size of the world. An obstacle whose box spans
more than :data:`MAX_CELLS` cells (a map, a long wall) is kept aside and always measured.
"""

from __future__ import annotations

import math
from collections import defaultdict

import numpy as np

from worlds import MAX_COORD_M, World

CELL_M = 1.0          # [m] grid cell
MAX_CELLS = 4096      # [-] cells one obstacle may be filed in before it is kept aside


class StaticIndex:
    """The static obstacles of ``world`` filed by place (module doc)."""

    def __init__(self, world: World, cell_m: float = CELL_M):
        self.world, self.cell = world, cell_m
        self.cells: dict[tuple[int, int], list[int]] = defaultdict(list)
        self.wide: list[int] = []      # obstacles measured by every query
        self.static = [i for i, ob in enumerate(world.obstacles) if ob.motion is None]
        for i in self.static:
            ob = world.obstacles[i]
            x0, y0, x1, y1 = ob.model.bounds(ob)
            i0, j0, i1, j1 = *self._cell(x0, y0), *self._cell(x1, y1)
            if (i1 - i0 + 1) * (j1 - j0 + 1) > MAX_CELLS:
                self.wide.append(i)
                continue
            for ci in range(i0, i1 + 1):
                for cj in range(j0, j1 + 1):
                    self.cells[(ci, cj)].append(i)

    def _cell(self, x: float, y: float) -> tuple[int, int]:
        return math.floor(x / self.cell), math.floor(y / self.cell)

    def near(self, x: float, y: float, radius_m: float) -> list[int]:
        """Indices of the static obstacles whose bounding box may lie within ``radius_m`` [m]
        of (x, y) [m] (a superset; sorted, each once)."""
        i0, j0 = self._cell(x - radius_m, y - radius_m)
        i1, j1 = self._cell(x + radius_m, y + radius_m)
        found = set(self.wide)
        for ci in range(i0, i1 + 1):
            for cj in range(j0, j1 + 1):
                found.update(self.cells.get((ci, cj), ()))
        return sorted(found)

    def nearest(self, x: float, y: float) -> int | None:
        """Index of the static obstacle nearest to (x, y) [m] (signed distance), or None.

        Looks one cell around first and widens until an obstacle is found within the searched
        radius (a nearer one outside it cannot exist); past the world's span, measures all."""
        radius = self.cell
        while True:
            everything = radius > 4 * MAX_COORD_M
            candidates = self.static if everything else self.near(x, y, radius)
            best = None
            for i in candidates:
                ob = self.world.obstacles[i]
                d = float(ob.model.distance(ob, np.array([[x, y]]))[0])
                if best is None or d < best[0]:
                    best = (d, i)
            if everything or (best is not None and best[0] <= radius):
                return None if best is None else best[1]
            radius *= 4
