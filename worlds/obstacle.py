"""One obstacle of a world, as parsed (:class:`Obstacle`); its kind's class does the rest.

``ob.model`` is the obstacle's kind (:data:`KINDS`, registered in :mod:`worlds.kinds`): its geometry, physics body
and drawing. Used by every module that reads a world's obstacles.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from worlds.traffic import Motion, ObstacleState, state_at

DEFAULT_HEIGHT = 0.5  # [m] obstacle height when the file gives none (docs/worlds.md)
# the kinds by TOML name -> their class instance; filled by worlds/kinds/__init__.py
KINDS: dict = {}


@dataclass(frozen=True)
class Obstacle:
    """One obstacle, normalised: walls become boxes (from/to/thickness -> center/size/yaw).

    ``kind`` keeps the file's kind (its class: :attr:`model`); ``shape`` is the primitive:
    ``box`` (``size`` = (sx, sy) before ``yaw``), ``cylinder`` (``radius``) or ``sphere``
    (``radius``, 3-D worlds: ``center`` has z).
    """

    kind: str
    shape: str
    center: tuple[float, ...]
    size: tuple[float, float] = (0.0, 0.0)
    radius: float = 0.0
    yaw: float = 0.0
    height: float = DEFAULT_HEIGHT
    motion: Motion | None = None  # a kinematic track; ``center``/``yaw`` are its pose at t = 0
    grid: object = field(default=None, compare=False, repr=False)  # a map's OccupancyMap

    @property
    def model(self):
        """The obstacle's kind (a :class:`worlds.kinds.base.Kind`)."""
        return KINDS[self.kind]

    @property
    def moving(self) -> bool:
        return self.motion is not None

    def state_at(self, t: float) -> ObstacleState:
        """Pose and velocity at sim time ``t`` [s] (a static obstacle: its pose, zero velocity)."""
        if self.motion is None:
            return ObstacleState(self.center[0], self.center[1], self.yaw, 0.0, 0.0)
        return state_at(self.motion, t)

    def at(self, t: float) -> Obstacle:
        """This obstacle placed where it is at sim time ``t`` [s] (itself when static)."""
        if self.motion is None:
            return self
        s = state_at(self.motion, t)
        return replace(self, center=(s.x, s.y), yaw=s.yaw)

    def corners(self) -> list[tuple[float, float]]:
        """The corners of the footprint's outline (counter-clockwise), world frame [m]."""
        return self.model.corners(self)
