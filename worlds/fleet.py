"""Several robots and people in one world: ``[[robots]]`` and ``[[people]]`` (docs/worlds.md).

``[[robots]]`` replaces ``[robot]`` and ``[goal]``: each entry is a ROSbot with its own
namespace (``name``), start, goal, tolerance and, optionally, planner. ``[[people]]`` are
pedestrians who walk to a goal (or along waypoints, optionally in a loop) at a preferred
speed and avoid the others, robots included, with ORCA or the social-force model. A person
with ``speed = 0``, or with neither goal nor waypoints, stands at ``start``. ``[[groups]]``
binds people who stand or walk together (``members``: indexes into ``[[people]]``; the
motion model is :mod:`common.crowd`'s, the measures treat a group as one).

Defaults (CrowdNav's, Chen et al. 2019): a person's radius 0.3 m and preferred speed
1.0 m/s. Limits keep a hostile file from asking for an unbounded crowd.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

PERSON_MODELS = ("orca", "social_force")
PERSON_RADIUS_M = 0.3          # [m] default body radius (CrowdNav)
PERSON_SPEED_M_S = 1.0         # [m/s] default preferred speed (CrowdNav v_pref)
MAX_PERSON_SPEED_M_S = 3.0     # [m/s] a running person
MAX_PERSON_RADIUS_M = 1.0      # [m]
MAX_ROBOTS = 32                # [-] robots in one world (fleet-ring-32 runs: docs/performance.md)
MAX_PEOPLE = 200               # [-] people in one world
MAX_WAYPOINTS = 1000           # [-] of one person
ROBOT_KEYS = ("name", "start", "goal", "tolerance", "planner")
PERSON_KEYS = ("start", "goal", "waypoints", "loop", "speed", "radius", "model")
GROUP_KEYS = ("members",)
MAX_GROUP_MEMBERS = 12         # [-] a group larger than this is a crowd (F-formations: 2-7)
_NAME = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.-]*")


@dataclass(frozen=True)
class RobotSpec:
    """One robot of ``[[robots]]`` (or the single ``[robot]``/``[goal]``, with name "")."""

    name: str                              # namespace; "" = the run's --namespace
    start: tuple[float, float, float]      # (x [m], y [m], yaw [rad])
    goal: tuple[float, float]              # [m]
    tolerance: float = 0.1                 # [m]
    planner: str | None = None             # None = the run's --planner


@dataclass(frozen=True)
class PersonSpec:
    """One pedestrian of ``[[people]]``: walks ``route`` (the goal, or the waypoints)."""

    start: tuple[float, float]             # [m]
    route: tuple[tuple[float, float], ...]  # goal or waypoints, in order [m]
    loop: bool = False                     # waypoints again from the first after the last
    speed: float = PERSON_SPEED_M_S        # [m/s] preferred
    radius: float = PERSON_RADIUS_M        # [m]
    model: str = "orca"                    # orca | social_force

    @property
    def standing(self) -> bool:
        """Stands at ``start`` for the whole run: speed 0, or no goal and no waypoints."""
        return self.speed == 0.0 or not self.route


@dataclass(frozen=True)
class GroupSpec:
    """One ``[[groups]]`` entry: people who stand or walk together."""

    members: tuple[int, ...]               # indexes into [[people]], each in one group at most

    def standing(self, people) -> bool:
        """Every member stands (a group stands or walks as a whole)."""
        return all(people[i].standing for i in self.members)


def parse_robots(ctx, raw) -> tuple[RobotSpec, ...]:
    """``[[robots]]`` -> specs; ``ctx`` is the world parser's field reader (WorldError)."""
    if not isinstance(raw, list) or not raw:
        ctx.fail("robots", "must be a non-empty array of tables ([[robots]])")
    if len(raw) > MAX_ROBOTS:
        ctx.fail("robots", f"{len(raw)} robots, more than {MAX_ROBOTS}")
    robots, names = [], set()
    for i, t in enumerate(raw):
        where = f"robots[{i}]"
        if not isinstance(t, dict):
            ctx.fail(where, "must be a table")
        name = ctx.str(t, "name", f"{where}.name")
        if len(name) > 64 or not _NAME.fullmatch(name):
            ctx.fail(f"{where}.name", f"{name!r} must be a plain key like 'r1' (letters, digits, "
                     "'_', '-', '.'; at most 64 characters)")
        if name in names:
            ctx.fail(f"{where}.name", f"{name!r} is used by another robot; names must differ")
        names.add(name)
        start = ctx.vec(t, "start", (2, 3), f"{where}.start")
        goal = ctx.vec(t, "goal", (2,), f"{where}.goal")
        planner = t.get("planner")
        if planner is not None:
            planner = ctx.str(t, "planner", f"{where}.planner")
        robots.append(RobotSpec(name=name, start=(*start, 0.0) if len(start) == 2 else tuple(start),
                                goal=tuple(goal), planner=planner,
                                tolerance=ctx.tolerance(t, "tolerance", f"{where}.tolerance")))
    return tuple(robots)


def parse_people(ctx, raw) -> tuple[PersonSpec, ...]:
    """``[[people]]`` -> specs (module doc for the defaults and limits)."""
    if not isinstance(raw, list):
        ctx.fail("people", "must be an array of tables ([[people]])")
    if len(raw) > MAX_PEOPLE:
        ctx.fail("people", f"{len(raw)} people, more than {MAX_PEOPLE}")
    people = []
    for i, t in enumerate(raw):
        where = f"people[{i}]"
        if not isinstance(t, dict):
            ctx.fail(where, "must be a table")
        start = tuple(ctx.vec(t, "start", (2,), f"{where}.start"))
        route = _route(ctx, t, where)
        loop = t.get("loop", False)
        if not isinstance(loop, bool):
            ctx.fail(f"{where}.loop", f"must be true or false, got {loop!r}")
        if loop and "waypoints" not in t:
            ctx.fail(f"{where}.loop", "only waypoints can loop (a goal is walked once)")
        speed = ctx.number(t, "speed", f"{where}.speed", default=PERSON_SPEED_M_S)
        if not 0.0 <= speed <= MAX_PERSON_SPEED_M_S:
            ctx.fail(f"{where}.speed", f"{speed:g} m/s is not a walking speed (valid: 0 to stand, "
                     f"up to {MAX_PERSON_SPEED_M_S:g} m/s)")
        radius = ctx.positive(t, "radius", f"{where}.radius", default=PERSON_RADIUS_M)
        if radius > MAX_PERSON_RADIUS_M:
            ctx.fail(f"{where}.radius", f"{radius:g} m is wider than a person "
                     f"(valid: (0, {MAX_PERSON_RADIUS_M:g}] m)")
        model = ctx.str(t, "model", f"{where}.model", default="orca")
        if model not in PERSON_MODELS:
            ctx.fail(f"{where}.model", f"{model!r} is not one of {', '.join(PERSON_MODELS)}")
        people.append(PersonSpec(start=start, route=route, loop=loop, speed=speed,
                                 radius=radius, model=model))
    return tuple(people)


def _route(ctx, t: dict, where: str) -> tuple[tuple[float, float], ...]:
    """A person's goal, or waypoints (at most one of the two; neither: the person stands)."""
    if "goal" in t and "waypoints" in t:
        ctx.fail(where, "give a goal = [x, y] or waypoints = [[x, y], ...], not both (neither: "
                 "the person stands at start)")
    if "goal" not in t and "waypoints" not in t:
        return ()
    if "goal" in t:
        return (tuple(ctx.vec(t, "goal", (2,), f"{where}.goal")),)
    points = t["waypoints"]
    if not isinstance(points, list) or not points or len(points) > MAX_WAYPOINTS:
        ctx.fail(f"{where}.waypoints", f"must be an array of 1 to {MAX_WAYPOINTS} "
                 f"points [x, y], got {str(points)[:80]}")
    return tuple(tuple(ctx.vec({"p": p}, "p", (2,), f"{where}.waypoints[{j}]"))
                 for j, p in enumerate(points))


def parse_groups(ctx, raw, people: tuple[PersonSpec, ...]) -> tuple[GroupSpec, ...]:
    """``[[groups]]`` -> specs: at least two members each, valid indexes into ``[[people]]``,
    nobody in two groups, a group all standing or all walking; a walking group's members
    walk routes of as many points, all looping or none (they walk side by side: each its
    own route, at the group's pace; common/crowd.py)."""
    if not isinstance(raw, list) or not raw:
        ctx.fail("groups", "must be a non-empty array of tables ([[groups]])")
    taken: dict[int, int] = {}
    groups = []
    for g, t in enumerate(raw):
        where = f"groups[{g}]"
        if not isinstance(t, dict):
            ctx.fail(where, "must be a table")
        members = t.get("members")
        if not isinstance(members, list) or not 2 <= len(members) <= MAX_GROUP_MEMBERS or not all(
                isinstance(m, int) and not isinstance(m, bool) for m in members):
            ctx.fail(f"{where}.members", f"must be 2 to {MAX_GROUP_MEMBERS} indexes into "
                     f"[[people]] (0 to {len(people) - 1}), got {str(members)[:80]}")
        for m in members:
            if not 0 <= m < len(people):
                ctx.fail(f"{where}.members", f"{m} is not a person: [[people]] has "
                         f"{len(people)} entries (0 to {len(people) - 1})")
            if m in taken:
                ctx.fail(f"{where}.members", f"people[{m}] is already in groups[{taken[m]}] "
                         "(a person belongs to one group)")
            taken[m] = g
        spec = GroupSpec(members=tuple(members))
        mine = [people[m] for m in members]
        if len({p.standing for p in mine}) > 1:
            ctx.fail(where, "its members must all stand or all walk (a group moves as one)")
        if not spec.standing(people) and (len({len(p.route) for p in mine}) > 1
                                          or len({p.loop for p in mine}) > 1):
            ctx.fail(where, "a walking group's members walk side by side: give each a route of "
                     "as many points (goal, or waypoints), all looping or none")
        groups.append(spec)
    return tuple(groups)
