"""What a run tells the stack about its world, as messages.

The planner never reads the world file (on the robot it isn't there): the launcher sends
the goal, and the goal carries the world's ``[road]`` (:func:`goal_message`).
"""

from __future__ import annotations

from schemas.messages import Goal
from worlds import World


def goal_message(world: World, stamp_ns: int = 0) -> Goal:
    """The goal handshake message of ``world``: goal position, tolerance and its road."""
    road = world.road
    return Goal(stamp_ns=stamp_ns, x=world.goal[0], y=world.goal[1], tolerance=world.tolerance,
                road_lanes=road.lanes if road else 0,
                road_y_min=road.y_min if road else 0.0,
                road_lane_width=road.lane_width if road else 0.0)
