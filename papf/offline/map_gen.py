"""SLAM-style occupancy maps made by code: rooms, a corridor, a warehouse, a campus (and a
large hall for ``papf bench world-scale``), each with the free cells inside, walls, and unknown
outside the building as a SLAM tool leaves it. Cell values are Nav2's (-1 unknown, 0 free,
100 occupied), row = y up. Used by the packaged map worlds, tests and the benchmark.
"""

from __future__ import annotations

import numpy as np

from worlds.maps import FREE, OCCUPIED, UNKNOWN

WALL_M = 0.1          # [m] wall thickness
MARGIN_M = 0.5        # [m] unknown band around the building


class Sketch:
    """A map being drawn in metres: :meth:`box` fills a rectangle with a cell value."""

    def __init__(self, width_m: float, height_m: float, res: float):
        self.res = res
        self.data = np.full((round(height_m / res), round(width_m / res)), UNKNOWN, np.int8)

    def box(self, x0: float, y0: float, x1: float, y1: float, value: int) -> Sketch:
        r = self.res
        self.data[round(y0 / r):round(y1 / r), round(x0 / r):round(x1 / r)] = value
        return self

    def building(self, w: float, h: float) -> Sketch:
        """Free floor inside walls, from (MARGIN, MARGIN) to (MARGIN + w, MARGIN + h) [m]."""
        m, t = MARGIN_M, WALL_M
        self.box(m, m, m + w, m + h, OCCUPIED)
        return self.box(m + t, m + t, m + w - t, m + h - t, FREE)


def rooms(res: float = 0.05) -> np.ndarray:
    """12 x 9 m: four rooms off a central hall, 1 m doors, a table in one room."""
    s = Sketch(13, 10, res).building(12, 9)
    m, t = MARGIN_M, WALL_M
    for x in (m + 4, m + 8):                       # two walls across, doors at y = 2..3, 6..7
        s.box(x, m, x + t, m + 9, OCCUPIED)
        s.box(x, m + 2, x + t, m + 3, FREE).box(x, m + 6, x + t, m + 7, FREE)
    s.box(m, m + 4.5, m + 4, m + 4.5 + t, OCCUPIED).box(m + 1.5, m + 4.5, m + 2.5, m + 4.6, FREE)
    return s.box(m + 9, m + 6.5, m + 10.5, m + 7.3, OCCUPIED).data


def corridor(res: float = 0.05) -> np.ndarray:
    """An L-shaped corridor, 1.6 m wide: 16 m along x, then 7 m up, alcoves and pillars."""
    s = Sketch(18, 9, res)
    m = MARGIN_M
    s.box(m, m, m + 17, m + 2, OCCUPIED).box(m + 15, m, m + 17, m + 8, OCCUPIED)
    s.box(m + 0.1, m + 0.2, m + 16.9, m + 1.8, FREE).box(m + 15.2, m + 0.2, m + 16.8, m + 7.9, FREE)
    for x in range(3, 13, 5):                      # alcoves and pillars along the corridor
        s.box(m + x, m + 1.8, m + x + 1.2, m + 1.95, FREE)
        s.box(m + x + 2, m + 0.2, m + x + 2.3, m + 0.5, OCCUPIED)
    return s.data


def warehouse(res: float = 0.05, width_m: float = 20.0, depth_m: float = 15.0) -> np.ndarray:
    """Racks 0.9 m deep in rows with 1.6 m aisles, a cross aisle, pallets here and there."""
    s = Sketch(width_m + 1, depth_m + 1, res).building(width_m, depth_m)
    m = MARGIN_M
    rng = np.random.default_rng(7)
    for y in np.arange(m + 2.0, m + depth_m - 2.0, 2.5):
        for x0 in (m + 2.0, m + width_m / 2 + 1.0):
            s.box(x0, y, x0 + width_m / 2 - 3.0, y + 0.9, OCCUPIED)
        px = m + 1.0 + rng.uniform(0, width_m - 2.5)
        s.box(px, y - 1.0, px + 0.6, y - 0.6, OCCUPIED)
    return s.data


def campus(res: float = 0.1, blocks: int = 6) -> np.ndarray:
    """A 100 x 100 m campus: ``blocks`` x ``blocks`` buildings (unknown inside, as a LiDAR
    never sees into them, with walls) along 6 m streets, benches, bins and bollards on the
    pavements, the whole site walled in."""
    size = 100.0
    s = Sketch(size + 1, size + 1, res).building(size, size)
    m, street = MARGIN_M, 6.0
    pitch = (size - street) / blocks
    side = pitch - street
    rng = np.random.default_rng(11)
    for i in range(blocks):
        for j in range(blocks):
            x0, y0 = m + street + i * pitch, m + street + j * pitch
            s.box(x0, y0, x0 + side, y0 + side, OCCUPIED)
            s.box(x0 + 0.3, y0 + 0.3, x0 + side - 0.3, y0 + side - 0.3, UNKNOWN)
    for _ in range(blocks * blocks * 3):               # street furniture near the kerbs
        k = rng.integers(0, blocks + 1)
        along = rng.uniform(m + 2.0, m + size - 2.0)
        kerb = m + k * pitch + rng.choice((0.6, street - 1.0))
        w, d = rng.choice(((0.3, 0.3), (1.5, 0.5), (0.5, 0.5)))
        if rng.random() < 0.5:
            s.box(along, kerb, along + w, kerb + d, OCCUPIED)
        else:
            s.box(kerb, along, kerb + d, along + w, OCCUPIED)
    return s.data


def hall(width_m: float, res: float, pillars: int = 400, seed: int = 3) -> np.ndarray:
    """A square hall ``width_m`` [m] with ``pillars`` 0.3 m pillars scattered (the bench)."""
    s = Sketch(width_m + 1, width_m + 1, res).building(width_m, width_m)
    rng = np.random.default_rng(seed)
    for x, y in rng.uniform(MARGIN_M + 2, MARGIN_M + width_m - 2, (pillars, 2)):
        s.box(x, y, x + 0.3, y + 0.3, OCCUPIED)
    return s.data
