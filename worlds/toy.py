"""Small worlds built in code and their exact scans: circles and segments as a
:class:`worlds.World`, and a noiseless 360-degree :class:`~schemas.messages.Scan` of one
(used by the planner tests, ``papf bench planner`` and the doc case studies)."""

from __future__ import annotations

import math

import numpy as np

from common import robot
from schemas.messages import Scan
from worlds import Obstacle, World
from worlds.geometry import cast_rays, segment_wall


def toy_world(circles=(), segments=(), start=(0.0, 0.0, 0.0), goal=(5.0, 0.0),
              tolerance: float = 0.1) -> World:
    """A world of ``circles`` (x, y, r) and ``segments`` (x0, y0, x1, y1) [m]."""
    obstacles = tuple(Obstacle("cylinder", "cylinder", (cx, cy), radius=r) for cx, cy, r in circles)
    obstacles += tuple(segment_wall(*seg) for seg in segments)
    return World("toy", "", tuple(start), tuple(goal), tolerance, obstacles)


def box_segments(cx: float, cy: float, sx: float, sy: float) -> tuple:
    """The 4 sides of an axis-aligned box as segments."""
    x0, x1, y0, y1 = cx - sx / 2, cx + sx / 2, cy - sy / 2, cy + sy / 2
    return ((x0, y0, x1, y0), (x1, y0, x1, y1), (x1, y1, x0, y1), (x0, y1, x0, y0))


def cast_scan(world: World, x: float, y: float, yaw: float, stamp_ns: int = 0,
              beams: int = 300, range_max: float = robot.LIDAR_RANGE_MAX_M) -> Scan:
    """Ranges of ``beams`` rays over 360 degrees from (x, y, yaw); inf = no return."""
    inc = 2.0 * math.pi / beams
    ranges = cast_rays(world, x, y, yaw + (-math.pi + inc * np.arange(beams)), range_max)
    return Scan(stamp_ns=stamp_ns, angle_min=-math.pi, angle_increment=inc,
                range_min=robot.LIDAR_RANGE_MIN_M, range_max=range_max,
                ranges=ranges.astype(np.float32))
