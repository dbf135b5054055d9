"""Can a world be run at all? Checks made before any process starts.

A world file can be valid TOML in the fixed format and still describe a run that cannot
succeed: :func:`check_runnable` refuses (WorldError, one line naming the problem) a start
inside an obstacle and a goal that no robot position within the tolerance can reach
without overlapping an obstacle. Coordinate bounds are checked when the file is parsed
(:data:`worlds.MAX_COORD_M`). The number of obstacles is not limited: many static ones
are merged into meshes (worlds/bullet.py; cost: docs/data/world-scale.csv).

Geometry: each obstacle kind's signed distance (worlds/kinds/).
"""

from __future__ import annotations

import numpy as np

from common.errors import WorldError
from common.robot import BODY_LENGTH_M, BODY_WIDTH_M
from worlds import Obstacle, World

START_CLEAR_M = min(BODY_LENGTH_M, BODY_WIDTH_M) / 2   # [m] the chassis' inscribed half-width


def signed_distance(ob: Obstacle, point: tuple[float, ...]) -> float:
    """Distance [m] from ``point`` to the obstacle's outline (< 0 inside), in the plane
    (3-D for spheres)."""
    return float(ob.model.distance(ob, np.asarray([point], dtype=float))[0])


def nearest_obstacle(world: World, point: tuple[float, ...]) -> tuple[int, float] | None:
    """(index, signed distance) of the obstacle nearest to ``point``, or None."""
    best = None
    for i, ob in enumerate(world.obstacles):
        if world.dims not in ob.model.world_dims:
            continue
        d = signed_distance(ob, point)
        if best is None or d < best[1]:
            best = (i, d)
    return best


def check_runnable(world: World, robot_radius_m: float = START_CLEAR_M) -> None:
    """WorldError when the world cannot give a run (module doc); with several robots or
    people, for each of them (:func:`check_fleet`)."""
    if world.robots or world.has_people:
        check_fleet(world, robot_radius_m)
        return
    _check_one(world, world.start, world.goal, world.tolerance, "", robot_radius_m)


def check_fleet(world: World, robot_radius_m: float = START_CLEAR_M) -> None:
    """Every robot's start and goal as :func:`check_runnable` checks one robot's; no two robots'
    footprints overlapping at their starts; no person starting inside an obstacle, a robot's
    footprint or another person."""
    from common.crowd_measures import box_box_distance

    where = f"world {world.name!r} ({world.source or 'no file'})"
    fleet = world.fleet
    for r in fleet:
        _check_one(world, r.start, r.goal, r.tolerance, r.name, robot_radius_m)
    for i, a in enumerate(fleet):
        for b in fleet[i + 1:]:
            if box_box_distance(a.start, b.start) <= 0.0:
                raise WorldError(f"{where}: robots {a.name!r} and {b.name!r} start with their "
                                 f"footprints overlapping at {_xy(a.start[:2])} and "
                                 f"{_xy(b.start[:2])}; move them apart")
    for k, person in enumerate(world.people):
        _check_person(world, k, person, fleet, where, robot_radius_m)


def _check_person(world: World, k: int, person, fleet, where: str, robot_radius_m: float) -> None:
    """people[k] off every obstacle, robot and earlier person; standing off every goal."""
    from common.crowd_measures import point_box_distance

    near = nearest_obstacle(world, person.start)
    if near is not None and near[1] < person.radius:
        raise WorldError(f"{where}: people[{k}] starts at {_xy(person.start)} inside "
                         f"obstacles[{near[0]}] ({world.obstacles[near[0]].kind})")
    for r in fleet:
        if point_box_distance(np.array([person.start]), *r.start)[0] < person.radius:
            who = f"robot {r.name!r}" if r.name else "the robot"
            raise WorldError(f"{where}: people[{k}] starts at {_xy(person.start)} on {who}'s "
                             "footprint; move one of them")
    for r in fleet if person.standing else ():
        if np.hypot(*np.subtract(person.start, r.goal)) < person.radius + robot_radius_m \
                - r.tolerance:
            who = f"robot {r.name!r}'s" if r.name else "the robot's"
            raise WorldError(f"{where}: people[{k}] stands at {_xy(person.start)} on "
                             f"{who} goal {_xy(r.goal)}, which can then never be reached; "
                             "move one of them")
    for j, other in enumerate(world.people[:k]):
        if np.hypot(*np.subtract(person.start, other.start)) < person.radius + other.radius:
            raise WorldError(f"{where}: people[{j}] and people[{k}] start overlapping at "
                             f"{_xy(other.start)} and {_xy(person.start)}")


def _check_one(world: World, start, goal, tolerance: float, name: str,
               robot_radius_m: float) -> None:
    """One robot's start off every obstacle and its goal reachable (module doc)."""
    where = f"world {world.name!r} ({world.source or 'no file'})"
    if name:
        where += f", robot {name!r}"
    start = start[:world.dims]
    near = nearest_obstacle(world, start)
    clear = 0.0 if world.dims == 3 else START_CLEAR_M
    if near is not None and near[1] < clear:
        ob = world.obstacles[near[0]]
        raise WorldError(f"{where}: the start {_xy(start)} is inside obstacles[{near[0]}] "
                         f"({ob.kind}); the robot would begin in a collision")
    near = nearest_obstacle(world, goal)
    need = (0.0 if world.dims == 3 else robot_radius_m) - tolerance
    if near is not None and near[1] < need:
        ob = world.obstacles[near[0]]
        raise WorldError(f"{where}: the goal {_xy(goal)} lies inside obstacles[{near[0]}] "
                         f"({ob.kind}); no position within the {tolerance:g} m tolerance "
                         "keeps the robot off it, so the goal can never be reached")


def _xy(p) -> str:
    return "(" + ", ".join(f"{v:g}" for v in p) + ")"
