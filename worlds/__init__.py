"""World files (docs/worlds.md, **fixed** TOML format): parse, validate, find by name.

``load_world("energy")`` finds a packaged world by name; any path to a ``.toml``
file works too. Every problem raises :class:`WorldError` naming the file, the
entry and what would be valid.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field, replace
from importlib import resources
from pathlib import Path

from common.errors import WorldError
from common.optional import tomllib
from common.robot import GOAL_TOLERANCE_MIN_M
from common.syntax import toml_problem
from common.text import suggest
from worlds.fleet import GroupSpec, PersonSpec, RobotSpec, parse_groups, parse_people, parse_robots
from worlds.kinds import KINDS  # noqa: F401 (re-exported: the kinds' TOML names -> classes)
from worlds.obstacle import DEFAULT_HEIGHT, Obstacle  # noqa: F401 (re-exported)
from worlds.people_replay import ReplaySpec, parse_replays
from worlds.traffic import Motion, Road, state_at
from worlds.validate import MAX_FILE_BYTES, check_document, check_text_size

VEHICLES = ("rosbot", "car")  # [robot].vehicle: the ROSbot stack, or the IAPF paper's car model
# [m] largest coordinate or size a world may use: the simulator works in single precision
# in places (LiDAR ranges) and a planner's 1/r^2 field vanishes long before; 1 km is far
# beyond any indoor robot's world
MAX_COORD_M = 1000.0
MAX_WORLD_ARG = 4096  # [chars] a world name or path given on the command line (PATH_MAX)
CENTER_MATCH = 1e-6  # [m] a moving obstacle's center, if given, must be its track at t = 0


@dataclass(frozen=True)
class World:
    name: str
    description: str
    start: tuple[float, float, float]           # (x, y, yaw) [m, m, rad]; (x, y, z) [m] in 3-D worlds
    goal: tuple[float, ...]                      # (x, y) or (x, y, z) [m]
    tolerance: float                             # [m]
    obstacles: tuple[Obstacle, ...] = field(default_factory=tuple)
    source: str = ""                             # file it came from
    road: Road | None = None                     # the optional ``[road]``
    vehicle: str = "rosbot"                      # ``[robot].vehicle``: rosbot | car (IAPF cases)
    robots: tuple[RobotSpec, ...] = ()           # ``[[robots]]`` (start/goal are the first's)
    people: tuple[PersonSpec, ...] = ()          # ``[[people]]``
    groups: tuple[GroupSpec, ...] = ()           # ``[[groups]]`` (indexes into people)
    people_replay: tuple[ReplaySpec, ...] = ()   # ``[[people_replay]]``: recorded people

    @property
    def has_people(self) -> bool:
        """People of any kind: ``[[people]]`` who react, or replayed ones."""
        return bool(self.people or self.people_replay)

    @property
    def replayed(self) -> tuple:
        """Every replayed person's track (:class:`worlds.people_replay.ReplayTrack`), in
        order: they follow the ``[[people]]`` in every people list of a run."""
        return tuple(tr for spec in self.people_replay for tr in spec.tracks)

    @property
    def n_people(self) -> int:
        """People in a run's people lists: ``[[people]]``, then the replayed ones."""
        return len(self.people) + sum(len(s.tracks) for s in self.people_replay)

    @property
    def fleet(self) -> tuple[RobotSpec, ...]:
        """Every robot: ``[[robots]]``, or the one of ``[robot]``/``[goal]`` (name "")."""
        return self.robots or (RobotSpec(name="", start=tuple(self.start[:3]),
                                         goal=tuple(self.goal[:2]), tolerance=self.tolerance),)

    @property
    def dims(self) -> int:
        return len(self.goal)

    @property
    def has_motion(self) -> bool:
        """True when any obstacle moves."""
        return any(ob.moving for ob in self.obstacles)

    def obstacles_at(self, t: float) -> tuple[Obstacle, ...]:
        """Every obstacle placed where it is at sim time ``t`` [s], in file order."""
        return tuple(ob.at(t) for ob in self.obstacles)


def packaged_worlds() -> list[str]:
    """Names of the worlds shipped with the package."""
    root = resources.files(__name__)
    return sorted(p.name[:-5] for p in root.iterdir() if p.name.endswith(".toml"))


def world_path(name_or_path: str | Path) -> Path:
    """Resolve a packaged world name or a file path; WorldError says what exists."""
    if len(str(name_or_path)) > MAX_WORLD_ARG:
        raise WorldError(f"world name or path of {len(str(name_or_path)):,} characters; a packaged "
                         f"world name or a path to a .toml file has at most {MAX_WORLD_ARG:,}")
    p = Path(name_or_path)
    # a directory of that name (e.g. an experiment's output "energy") is not a world file
    if p.suffix == ".toml" or p.is_file() or "/" in str(name_or_path):
        if not p.is_file():
            raise WorldError(f"world file {str(p)!r} does not exist; give a packaged world name "
                             f"({', '.join(packaged_worlds())}) or a path to a .toml file")
        return p
    packaged = resources.files(__name__) / f"{name_or_path}.toml"
    if not packaged.is_file():
        names = packaged_worlds()   # a misspelt name: the nearest packaged ones first
        near = suggest(str(name_or_path), names, quote=True)
        raise WorldError(f"no packaged world named {str(name_or_path)!r}{near or ';'} "
                         f"{'P' if near else 'p'}ackaged worlds: {', '.join(names)} (or pass "
                         "a path to a .toml file)")
    return Path(str(packaged))


def load_world(name_or_path: str | Path) -> World:
    """Load and validate a world by packaged name or path."""
    path = world_path(name_or_path)
    return parse_world(world_data(path), source=str(path))


def world_data(name_or_path: str | Path) -> dict:
    """A world file's decoded TOML, not yet validated (to derive variants: :func:`parse_world`)."""
    path = world_path(name_or_path)
    try:
        with path.open("rb") as fh:   # at most one byte past the limit is read
            raw = fh.read(MAX_FILE_BYTES + 1)
        check_text_size(len(raw) if len(raw) <= MAX_FILE_BYTES else path.stat().st_size, str(path))
        text = raw.decode("utf-8")
        return tomllib.loads(text)
    except (OSError, UnicodeDecodeError) as exc:
        raise WorldError(f"cannot read world file {str(path)!r}: {exc}") from None
    except tomllib.TOMLDecodeError as exc:
        raise WorldError(f"world file {str(path)!r} is not valid TOML: "
                         f"{toml_problem(exc, text)}") from None
    except RecursionError:
        raise WorldError(f"world file {str(path)!r}: tables or arrays nested too deeply") from None


# A world's name names files (recordings, reports, an experiment's runs) and is printed: no path
# separators, no control characters (an ESC sequence would run in the terminal), not hidden.
MAX_NAME_CHARS = 100
_WORLD_NAME = re.compile(rf"[\w+\-][\w .+\-]{{0,{MAX_NAME_CHARS - 1}}}")


def _world_name(ctx, data: dict, source: str) -> str:
    """``name``, a plain name (:data:`_WORLD_NAME`); without one, the file's stem made plain
    (any other character becomes ``_``: a file may be called anything)."""
    if "name" not in data:
        stem = re.sub(r"[^\w .+\-]", "_", Path(source).stem).lstrip(". ")
        return stem[:MAX_NAME_CHARS] or "world"
    name = ctx.str(data, "name")
    if not _WORLD_NAME.fullmatch(name):
        shown = repr(name if len(name) <= 60 else name[:57] + "...")
        ctx.fail("name", f"{shown} must be a plain name (letters, digits, spaces and '-', '_', "
                 f"'.', '+'; not starting with '.'; at most {MAX_NAME_CHARS} characters): runs, "
                 "recordings and reports are named after it")
    return name


def parse_world(data: dict, source: str = "<dict>") -> World:
    """Validate a decoded TOML document as a world (keys and limits first: :mod:`worlds.validate`)."""
    check_document(data, source)
    ctx = _Ctx(source)
    name = _world_name(ctx, data, source)
    robots = ()
    if "robots" in data:
        for table in ("robot", "goal"):
            if table in data:
                ctx.fail(f"[{table}]", "a world with [[robots]] gives each robot its start and goal "
                         "there; remove [robot] and [goal]")
        robots = parse_robots(ctx, data["robots"])
        first = robots[0]
        data = {**data, "robot": {"start": list(first.start)},
                "goal": {"position": list(first.goal), "tolerance": first.tolerance}}
    people, groups, replays = _people(ctx, data, source)
    robot = ctx.table(data, "robot", default={})
    start = ctx.vec(robot, "start", (2, 3), "robot.start", default=[0.0, 0.0, 0.0])
    vehicle = ctx.str(robot, "vehicle", "robot.vehicle", default="rosbot")
    if vehicle not in VEHICLES:
        ctx.fail("robot.vehicle", f"{vehicle!r} is not one of {', '.join(VEHICLES)}")
    if len(start) == 2:
        start = (*start, 0.0)
    goal_t = ctx.table(data, "goal")
    goal = ctx.vec(goal_t, "position", (2, 3), "goal.position")
    tolerance = ctx.tolerance(goal_t, "tolerance", "goal.tolerance")
    obstacles = []
    raw = data.get("obstacles", [])
    if not isinstance(raw, list):
        ctx.fail("obstacles", "must be an array of tables ([[obstacles]])")
    for i, ob in enumerate(raw):
        obstacles.append(_obstacle(ctx, ob, f"obstacles[{i}]", len(goal)))
    if "map" in data:   # the map's walls: one obstacle after the file's (worlds/kinds/grid.py)
        obstacles.append(KINDS["map"].parse(ctx, data["map"], "[map]"))
    road = _road(ctx, data["road"]) if "road" in data else None
    if road is not None and len(goal) != 2:
        ctx.fail("[road]", "a road needs a 2-D world (goal.position with 2 numbers)")
    if (robots or people or replays) and (len(goal) != 2 or vehicle != "rosbot"):
        ctx.fail("[[robots]]" if robots else "[[people]]" if people else "[[people_replay]]",
                 "several robots and people share a 2-D world of ROSbots")
    return World(name=name, description=ctx.str(data, "description", default=""),
                 start=tuple(start), goal=tuple(goal), tolerance=tolerance,
                 obstacles=tuple(obstacles), source=source, road=road,
                 vehicle=vehicle, robots=robots, people=people, groups=groups,
                 people_replay=replays)


def _people(ctx: _Ctx, data: dict, source: str) -> tuple:
    """``[[people]]``, ``[[groups]]`` (of those people), ``[[people_replay]]`` (files read)."""
    people = parse_people(ctx, data["people"]) if "people" in data else ()
    groups = parse_groups(ctx, data["groups"], people) if "groups" in data else ()
    replays = parse_replays(ctx, data["people_replay"], source, MAX_COORD_M) if "people_replay" in data else ()
    return people, groups, replays


def _road(ctx: _Ctx, t) -> Road:
    if not isinstance(t, dict):
        ctx.fail("[road]", "must be a table with y_min, lane_width, lanes")
    lanes = t.get("lanes", ctx._MISSING)
    if lanes is ctx._MISSING:
        ctx.fail("road.lanes", "is missing")
    if isinstance(lanes, bool) or not isinstance(lanes, int) or lanes < 1:
        ctx.fail("road.lanes", f"must be an integer >= 1, got {lanes!r}")
    return Road(y_min=ctx.number(t, "y_min", "road.y_min"),
                lane_width=ctx.positive(t, "lane_width", "road.lane_width"), lanes=lanes)


def _motion(ctx: _Ctx, t, where: str, yaw0: float) -> Motion:
    """``[obstacles.motion]``: a track of [t, x, y] samples, t strictly increasing."""
    if not isinstance(t, dict):
        ctx.fail(where, "must be a table with a track = [[t, x, y], ...]")
    raw = t.get("track", ctx._MISSING)
    if raw is ctx._MISSING:
        ctx.fail(f"{where}.track", "is missing")
    if not isinstance(raw, list) or not raw:
        ctx.fail(f"{where}.track", f"must be a non-empty array of [t s, x m, y m], got {raw!r}")
    track = []
    for i, sample in enumerate(raw):
        track.append(tuple(ctx.vec({"s": sample}, "s", (3,), f"{where}.track[{i}]",
                                   bounded=slice(1, 3))))   # x, y; not the time
        if i and track[i][0] <= track[i - 1][0]:
            ctx.fail(f"{where}.track[{i}]", f"time {track[i][0]} s must be after the previous "
                     f"sample's {track[i - 1][0]} s (times strictly increasing)")
    return Motion(track=tuple(track), yaw0=yaw0)


def _obstacle(ctx: _Ctx, ob: dict, where: str, dims: int) -> Obstacle:
    if not isinstance(ob, dict):
        ctx.fail(where, "must be a table")
    kind = ctx.str(ob, "kind", where=f"{where}.kind")
    if kind not in KINDS or not KINDS[kind].listed:
        listed = ", ".join(k for k, m in KINDS.items() if m.listed)
        ctx.fail(f"{where}.kind", f"{kind!r} is not one of {listed}")
    model = KINDS[kind]
    if "motion" not in ob:
        return model.parse(ctx, ob, where)
    if not model.movable or dims != 2:
        movers = ", ".join(k.name for k in KINDS.values() if k.movable)
        ctx.fail(f"{where}.motion", f"only 2-D kinds ({movers}) in 2-D worlds may move")
    motion = _motion(ctx, ob["motion"], f"{where}.motion", 0.0)
    start = state_at(motion, 0.0)
    given = ob.get("center")
    static = model.parse(ctx, {"center": [start.x, start.y], **ob}, where)
    if given is not None and math.dist(static.center, (start.x, start.y)) > CENTER_MATCH:
        ctx.fail(f"{where}.center", f"{list(static.center)} is not where the track is at t = 0 "
                 f"({[start.x, start.y]}); omit center on a moving obstacle or make them agree")
    yaw0 = ctx.number(ob, "yaw", f"{where}.yaw", default=static.yaw)
    motion = replace(motion, yaw0=yaw0)
    return replace(static, center=(start.x, start.y), motion=motion,
                   yaw=state_at(motion, 0.0).yaw)


class _Ctx:
    """Field readers that raise WorldError naming file, entry and expectation."""

    _MISSING = object()

    def __init__(self, source: str):
        self.source = source

    def fail(self, where: str, problem: str):
        raise WorldError(f"world {self.source!r}: {where}: {problem}")

    def _get(self, t: dict, key: str, where: str, default):
        if key in t:
            return t[key]
        if default is self._MISSING:
            self.fail(where, "is missing")
        return default

    def table(self, t: dict, key: str, default=_MISSING) -> dict:
        v = self._get(t, key, f"[{key}]", default)
        if not isinstance(v, dict):
            self.fail(f"[{key}]", "must be a table")
        return v

    def str(self, t: dict, key: str, where: str | None = None, default=_MISSING) -> str:
        v = self._get(t, key, where or key, default)
        if not isinstance(v, str):
            self.fail(where or key, f"must be a string, got {v!r}")
        return v

    def number(self, t: dict, key: str, where: str, default=_MISSING) -> float:
        v = self._get(t, key, where, default)
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            self.fail(where, f"must be a finite number, got {v!r}")
        if abs(v) > MAX_COORD_M:
            self.fail(where, f"{v:g} is beyond the {MAX_COORD_M:g} m a world may span")
        return float(v)

    def positive(self, t: dict, key: str, where: str, default=_MISSING) -> float:
        v = self.number(t, key, where, default)
        if v <= 0:
            self.fail(where, f"must be > 0, got {v}")
        return v

    def tolerance(self, t: dict, key: str, where: str) -> float:
        """A goal tolerance [m]: at least GOAL_TOLERANCE_MIN_M (common/robot.py), default 0.1."""
        v = self.number(t, key, where, 0.1)
        if not v >= GOAL_TOLERANCE_MIN_M:
            self.fail(where, f"must be at least {GOAL_TOLERANCE_MIN_M:g} m (a smaller tolerance "
                             f"is never reached), got {v}")
        return v

    def vec(self, t: dict, key: str, lengths: tuple[int, ...], where: str, default=_MISSING,
            bounded: slice = slice(None)):
        v = self._get(t, key, where, default)
        ok = isinstance(v, list) and len(v) in lengths and all(
            isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) for x in v)
        if not ok:
            want = " or ".join(f"{n} numbers" for n in lengths)
            self.fail(where, f"must be an array of {want}, got {v!r}")
        if any(abs(x) > MAX_COORD_M for x in v[bounded]):
            self.fail(where, f"{v} is beyond the {MAX_COORD_M:g} m a world may span")
        return [float(x) for x in v]
