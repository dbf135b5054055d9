"""What an obstacle kind is: the :class:`Kind` base class and the drawing primitives.

A kind owns its parsing from the world TOML (:meth:`Kind.parse`), its geometry
(:meth:`Kind.distance`, :meth:`Kind.cast`), its pybullet body (:meth:`Kind.body`) and
how it is drawn — as primitives (:class:`Outline`, :class:`Disc`, :class:`Raster`,
:class:`Solid`) that
``papf.plots.world`` and ``nodes.viewer.scene`` turn into artists. A new kind: one module
under ``worlds/kinds/`` and one line in ``worlds/kinds/__init__.py`` (docs/architecture.md,
"Extending").
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from worlds.obstacle import DEFAULT_HEIGHT, Obstacle


@dataclass(frozen=True)
class Outline:
    """A filled polygon in the plane: ``points`` [(x, y)] [m], counter-clockwise."""

    points: tuple[tuple[float, float], ...]


@dataclass(frozen=True)
class Disc:
    """A filled circle in the plane: ``center`` (x, y) [m], ``radius`` [m]."""

    center: tuple[float, float]
    radius: float


@dataclass(frozen=True, eq=False)
class Raster:
    """Cells of a grid in the plane: ``cells`` bool [row = y, col = x], cell (0, 0)'s corner
    at ``origin`` (x, y) [m], turned by ``yaw`` [rad], ``resolution`` [m/cell]."""

    cells: np.ndarray
    origin: tuple[float, float]
    yaw: float
    resolution: float


@dataclass(frozen=True)
class Solid:
    """A 3-D primitive: ``form`` cube | cylinder | sphere; ``center`` (x, y, z) [m], ``yaw``
    [rad], ``size`` (sx, sy, sz) [m] (cylinder: diameter, diameter, height)."""

    form: str
    center: tuple[float, float, float]
    size: tuple[float, float, float]
    yaw: float = 0.0


class Kind:
    """One obstacle kind. Methods take the parsed :class:`Obstacle`; ``pts`` are (N, D) [m]."""

    name = ""              # the TOML ``kind`` string
    world_dims = (2,)      # world dimensions it is an obstacle in (2: planar, 3: Wang's 3-D)
    movable = True         # may carry ``[obstacles.motion]``
    round = False          # a circle/sphere of ``radius`` about ``center`` (Wang's point sims)
    listed = True          # written as ``[[obstacles]]`` (False: its own table, e.g. ``[map]``)
    trackable = True       # an object the ground-truth ``objects`` message reports
    keys: tuple = ()       # the TOML keys its table may have besides ``kind`` (worlds/validate.py)

    def parse(self, ctx, table: dict, where: str) -> Obstacle:
        """The obstacle of one ``[[obstacles]]`` table; ``ctx`` raises WorldError (worlds._Ctx)."""
        raise NotImplementedError

    def table(self, ob: Obstacle) -> dict:
        """The TOML keys that parse back to ``ob`` (``kind`` included)."""
        raise NotImplementedError

    def distance(self, ob: Obstacle, pts: np.ndarray) -> np.ndarray:
        """Signed distance from each point to the outline [m] (< 0 inside)."""
        raise NotImplementedError

    def cast(self, ob: Obstacle, x: float, y: float, dx: np.ndarray, dy: np.ndarray,
             best: np.ndarray, range_max: float = float("inf")) -> np.ndarray:
        """``best`` lowered where the ray from (x, y) along (dx, dy) hits first [m]
        (hits beyond ``range_max`` [m] may be left out)."""
        raise NotImplementedError

    def corners(self, ob: Obstacle) -> list[tuple[float, float]]:
        """Corners of a polygonal footprint; ValueError for round kinds."""
        raise ValueError(f"{ob.kind} has no corners")

    def bounds(self, ob: Obstacle) -> tuple[float, float, float, float]:
        """(x0, y0, x1, y1) [m]: the footprint's axis-aligned bounding box."""
        raise NotImplementedError

    def reach(self, ob: Obstacle) -> float:
        """[m] a radius about ``center`` the footprint never leaves (may be loose)."""
        raise NotImplementedError

    def footprint(self, ob: Obstacle) -> tuple[float, float]:
        """(length along the heading, width across it) [m]."""
        raise NotImplementedError

    def pose(self, p, ob: Obstacle) -> tuple[list[float], list[float]]:
        """pybullet base position (the shape's centre) [m] and orientation quaternion
        (``p``: the pybullet module): standing on ``z = 0``, turned by ``yaw``."""
        quat = p.getQuaternionFromEuler([0.0, 0.0, ob.yaw])
        return [ob.center[0], ob.center[1], ob.height / 2], list(quat)

    def body(self, p, client_id: int, ob: Obstacle) -> int:
        """A pybullet collision shape id for ``ob`` (``p``: the pybullet module)."""
        raise NotImplementedError

    def bodies(self, p, client_id: int, ob: Obstacle) -> list[int]:
        """The collision shapes of ``ob``, each a static body at :meth:`pose` (one by default)."""
        return [self.body(p, client_id, ob)]

    def triangles(self, ob: Obstacle) -> tuple[np.ndarray, np.ndarray] | None:
        """(vertices (V, 3) [m, world frame], faces (F, 3) vertex indices) of the solid, for a
        static world of many obstacles merged into meshes (worlds/bullet.py); None: never merged."""
        return None

    def drawing(self, ob: Obstacle) -> Outline | Disc | Raster:
        """The footprint to draw in a top view."""
        raise NotImplementedError

    def solids(self, ob: Obstacle) -> list[Solid]:
        """The 3-D primitives to draw in the viewer."""
        raise NotImplementedError


def height_of(ctx, table: dict, where: str) -> float:
    """``height`` [m] of an ``[[obstacles]]`` table (default :data:`DEFAULT_HEIGHT`)."""
    return ctx.positive(table, "height", f"{where}.height", default=DEFAULT_HEIGHT)
