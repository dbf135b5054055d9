"""Roads and moving obstacles of a world (the **fixed** ``[road]`` and ``[obstacles.motion]``).

Pure geometry, no pybullet, no file reading — the parser in :mod:`worlds` builds these,
the sim, the offline planner and the plots use them.

- :class:`Road`: a straight one-way road along +x. ``y_min`` is the right edge (solid
  line), ``lanes`` lanes of ``lane_width`` are stacked towards +y, broken lines between
  them, a solid line at the left edge ``y_max``. The road is lines on the floor, not walls.
- :class:`Motion`: an obstacle's ``track`` of ``(t [s], x [m], y [m])`` samples over sim
  time. :func:`pose_at` interpolates linearly between samples and holds the first/last
  sample before/after; the heading is the direction of travel of the current segment,
  kept while standing, and the obstacle's ``yaw`` before the first move.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass

STANDING_EPS = 1e-9  # [m] a segment shorter than this is standing, not moving
EDGE_EPS = 1e-9      # [m] rounding allowance of the on-road test at the solid lines


@dataclass(frozen=True)
class RoadLine:
    """One painted line of a road: ``y`` [m] and ``kind`` (``solid`` | ``broken``)."""

    y: float
    kind: str


@dataclass(frozen=True)
class Road:
    """A straight one-way road along +x (fixed world format ``[road]``)."""

    y_min: float       # [m] right road edge (solid line)
    lane_width: float  # [m] d_w
    lanes: int         # [-] lanes stacked towards +y

    @property
    def y_max(self) -> float:
        """[m] the left road edge (solid line)."""
        return self.y_min + self.lanes * self.lane_width

    def lines(self) -> tuple[RoadLine, ...]:
        """The painted lines, right to left: solid edge, broken lines between lanes, solid edge."""
        inner = tuple(RoadLine(self.y_min + i * self.lane_width, "broken")
                      for i in range(1, self.lanes))
        return (RoadLine(self.y_min, "solid"), *inner, RoadLine(self.y_max, "solid"))

    @classmethod
    def from_fields(cls, lanes: int, y_min: float, lane_width: float) -> Road | None:
        """The road a goal message describes (``lanes = 0``: no road -> None)."""
        if lanes <= 0:
            return None
        return cls(y_min=float(y_min), lane_width=float(lane_width), lanes=int(lanes))

    def lane_centres(self) -> tuple[float, ...]:
        """[m] y of each lane's centre line, lane 0 (rightmost) first."""
        return tuple(self.y_min + (i + 0.5) * self.lane_width for i in range(self.lanes))

    def on_road(self, y: float) -> bool:
        """True when ``y`` lies between the two solid lines (inclusive)."""
        return self.y_min - EDGE_EPS <= y <= self.y_max + EDGE_EPS

    def lane_of(self, y: float) -> int:
        """Index of the lane that contains ``y`` (clamped to the road: 0 … lanes-1)."""
        i = math.floor((y - self.y_min) / self.lane_width)
        return min(max(i, 0), self.lanes - 1)


@dataclass(frozen=True)
class Motion:
    """A kinematic track: samples ``(t [s], x [m], y [m])`` with strictly increasing t."""

    track: tuple[tuple[float, float, float], ...]
    yaw0: float = 0.0  # [rad] heading before the first move (the obstacle's ``yaw``)

    @property
    def t_end(self) -> float:
        """[s] time of the last sample; the obstacle stands still after it."""
        return self.track[-1][0]


@dataclass(frozen=True)
class ObstacleState:
    """Where a (possibly moving) obstacle is at one sim time."""

    x: float    # [m]
    y: float    # [m]
    yaw: float  # [rad] heading (direction of travel)
    vx: float   # [m/s]
    vy: float   # [m/s]


def _segment(track: tuple[tuple[float, float, float], ...], t: float) -> int:
    """Index i of the segment track[i] -> track[i+1] that holds t; -1 before, len-1 after."""
    times = [s[0] for s in track]
    return bisect.bisect_right(times, t) - 1


def _moves(a: tuple[float, float, float], b: tuple[float, float, float]) -> bool:
    return math.hypot(b[1] - a[1], b[2] - a[2]) > STANDING_EPS


def heading_at(motion: Motion, t: float) -> float:
    """[rad] direction of travel at ``t``; the last one while standing; ``yaw0`` before any move."""
    track = motion.track
    i = min(_segment(track, t), len(track) - 2)
    for j in range(i, -1, -1):
        a, b = track[j], track[j + 1]
        if _moves(a, b):
            return math.atan2(b[2] - a[2], b[1] - a[1])
    return motion.yaw0


def state_at(motion: Motion, t: float) -> ObstacleState:
    """Position, heading and velocity of a track at sim time ``t`` [s] (linear interpolation).

    Before the first sample the first position is held, after the last the last one;
    the velocity is the current segment's (0 outside the track and while standing).
    """
    track = motion.track
    i = _segment(track, t)
    if i < 0 or i >= len(track) - 1:
        s = track[0] if i < 0 else track[-1]
        return ObstacleState(s[1], s[2], heading_at(motion, t), 0.0, 0.0)
    (t0, x0, y0), (t1, x1, y1) = track[i], track[i + 1]
    f = (t - t0) / (t1 - t0)
    vx, vy = (x1 - x0) / (t1 - t0), (y1 - y0) / (t1 - t0)
    return ObstacleState(x0 + f * (x1 - x0), y0 + f * (y1 - y0), heading_at(motion, t), vx, vy)


def pose_at(motion: Motion, t: float) -> tuple[float, float, float]:
    """``(x [m], y [m], yaw [rad])`` of a track at sim time ``t`` [s]."""
    s = state_at(motion, t)
    return s.x, s.y, s.yaw
