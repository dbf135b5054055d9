"""What a run tells the stack about its world, as messages.

The planner never reads the world file (on the robot it isn't there): the launcher sends
the goal, and the goal carries the world's ``[road]`` (:func:`goal_message`). The
simulated LiDAR publishes the sim's ground truth of the obstacles, people and other
robots as the same ``Objects`` message the tracker node derives from scans
(:func:`truth_objects`).
"""

from __future__ import annotations

import math

from common import robot
from schemas.messages import Bodies, Goal, Objects, ObjectTrack
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
                  max_range: float = math.inf, bodies: Bodies | None = None) -> Objects:
    """Ground truth at sim time ``stamp_ns``: every obstacle, and every person and other
    robot of ``bodies`` (the driver's ``sim/bodies`` of that instant), whose centre lies
    within ``max_range`` [m] of ``near`` (all when ``near`` is None).

    ``id``: an obstacle's index in the file; then the people (``n_obstacles + k``, k their
    index in ``[[people]]``), then the robots (``n_obstacles + n_people + j``, j their
    index in ``[[robots]]``), so every id is stable for the run. A person is a disc
    (length = width = its diameter, heading = its direction of travel, 0 standing); a robot
    is the ROSbot's chassis box at its heading."""
    t = stamp_ns * 1e-9
    tracks = []

    def add(i: int, x: float, y: float, **kw) -> None:
        if near is None or math.hypot(x - near[0], y - near[1]) <= max_range:
            tracks.append(ObjectTrack(id=i, x=x, y=y, **kw))

    for i, ob in enumerate(world.obstacles):
        if not ob.model.trackable:
            continue
        s = ob.state_at(t)
        length, width = footprint(ob)
        add(i, s.x, s.y, yaw=s.yaw, vx=s.vx, vy=s.vy, length=length, width=width)
    if bodies is not None:
        first = len(world.obstacles)
        for k, r in enumerate(bodies.person_radius):
            if not r > 0:       # a replayed person not in the scene now
                continue
            vx, vy = _velocity(bodies.person_vx, bodies.person_vy, k)
            add(first + k, bodies.person_x[k], bodies.person_y[k],
                yaw=math.atan2(vy, vx) if vx or vy else 0.0, vx=vx, vy=vy,
                length=2 * r, width=2 * r)
        first += world.n_people
        index = {spec.name: j for j, spec in enumerate(world.robots)}
        for k, name in enumerate(bodies.robots):
            vx, vy = _velocity(bodies.robot_vx, bodies.robot_vy, k)
            add(first + index.get(name, k), bodies.robot_x[k], bodies.robot_y[k],
                yaw=bodies.robot_yaw[k], vx=vx, vy=vy, length=robot.BODY_LENGTH_M,
                width=robot.BODY_WIDTH_M)
    return Objects(stamp_ns=stamp_ns, source="truth", tracks=tuple(tracks))


def _velocity(vx: tuple[float, ...], vy: tuple[float, ...], k: int) -> tuple[float, float]:
    """Body ``k``'s velocity [m/s]; (0, 0) from a ``Bodies`` recorded without velocities."""
    return (float(vx[k]), float(vy[k])) if k < len(vx) and k < len(vy) else (0.0, 0.0)
