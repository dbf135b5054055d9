"""What a run tells the stack about its world, as messages.

The planner never reads the world file (on the robot it isn't there): the launcher sends
the goal, and the goal carries the world's ``[road]`` (:func:`goal_message`). The
simulated LiDAR publishes the sim's ground truth of the obstacles as the same
``Objects`` message the tracker node derives from scans (:func:`truth_objects`).
"""

from __future__ import annotations

import math

from schemas.messages import Goal, Objects, ObjectTrack
from worlds import Obstacle, World


def goal_message(world: World, stamp_ns: int = 0) -> Goal:
    """The goal handshake message of ``world``: goal position, tolerance and its road."""
    road = world.road
    return Goal(stamp_ns=stamp_ns, x=world.goal[0], y=world.goal[1], tolerance=world.tolerance,
                road_lanes=road.lanes if road else 0,
                road_y_min=road.y_min if road else 0.0,
                road_lane_width=road.lane_width if road else 0.0)


def footprint(ob: Obstacle) -> tuple[float, float]:
    """(length along the heading, width across it) [m] of a 2-D obstacle's footprint."""
    return ob.model.footprint(ob)


def truth_objects(world: World, stamp_ns: int, near: tuple[float, float] | None = None,
                  max_range: float = math.inf) -> Objects:
    """Ground truth at sim time ``stamp_ns``: every obstacle whose centre lies within
    ``max_range`` [m] of ``near`` (all when ``near`` is None); ``id`` = index in the file."""
    t = stamp_ns * 1e-9
    tracks = []
    for i, ob in enumerate(world.obstacles):
        if not ob.model.trackable:
            continue
        s = ob.state_at(t)
        if near is not None and math.hypot(s.x - near[0], s.y - near[1]) > max_range:
            continue
        length, width = footprint(ob)
        tracks.append(ObjectTrack(id=i, x=s.x, y=s.y, yaw=s.yaw, vx=s.vx, vy=s.vy,
                                  length=length, width=width))
    return Objects(stamp_ns=stamp_ns, source="truth", tracks=tuple(tracks))
