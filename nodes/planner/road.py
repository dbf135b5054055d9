"""What a run tells a planner beyond scan and odometry: the road (:class:`Lanes`, from the
goal handshake) and the obstacle tracks (:class:`Track`, from ``<ns>/objects``).

The planner core keeps them (:class:`nodes.planner.core.Planner`) and hands them to its
strategy's ``observe``; the offline car simulation (papf/offline/) builds them from a world.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple


class Lanes(NamedTuple):
    """A straight one-way road along +x: ``y_min`` [m] right solid line, ``width`` [m] d_w."""

    y_min: float
    width: float
    count: int

    @property
    def y_max(self) -> float:
        """[m] left solid line."""
        return self.y_min + self.count * self.width

    def lane_of(self, y: float) -> int:
        """Index of the lane holding ``y`` (clamped to 0 … count-1)."""
        return min(max(int(math.floor((y - self.y_min) / self.width)), 0), self.count - 1)

    def centre(self, lane: int) -> float:
        """[m] y of a lane's centre line."""
        return self.y_min + (lane + 0.5) * self.width

    def nearest_boundary(self, y: float) -> float:
        """[m] y of the solid line nearer to ``y`` (Algorithm 1's y_nb)."""
        return self.y_min if y - self.y_min <= self.y_max - y else self.y_max


@dataclass(frozen=True)
class Track:
    """One obstacle as the planner sees it: pose, velocity and footprint (world frame)."""

    x: float            # [m]
    y: float            # [m]
    yaw: float          # [rad] heading phi of eq. 10
    vx: float = 0.0     # [m/s]
    vy: float = 0.0     # [m/s]
    length: float = 0.0  # [m] along the heading
    width: float = 0.0   # [m]
    id: int = 0

    @property
    def speed(self) -> float:
        """[m/s] v_o of eq. 9."""
        return math.hypot(self.vx, self.vy)

    def moved(self, dt: float) -> Track:
        """Where a constant-velocity obstacle is ``dt`` [s] later (Algorithm 1, Step 1)."""
        return Track(self.x + self.vx * dt, self.y + self.vy * dt, self.yaw, self.vx, self.vy,
                     self.length, self.width, self.id)
