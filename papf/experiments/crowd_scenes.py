"""The crowd experiment's scenes: the hall of walkers, standing groups, replayed recordings.

All share the hall (walls ``HALL_X`` x ``HALL_Y``, the robot from (0, 0) to (8, 0)):

- :func:`crowd_scene` - ``people`` walkers, drawn as the module doc of
  :mod:`papf.experiments.crowd` says;
- :func:`groups_scene` - people who stand and talk and people who walk together. Seeded
  from ``default_rng([seed, GROUPS_SALT])``: ``STANDING_GROUPS`` groups of three standing in
  a circle (an F-formation: members 0.45 m from its centre, facing in), the first centred
  within 0.6 m of the robot's line at x in 2.5-5.5 m (in its way), the other anywhere; two
  people standing alone; one pair walking side by side across the hall and back (a walking
  group); four walkers as the hall's (along and across, in a loop).
- :func:`replay_scene` - a track file replayed blind to the robot (``[[people_replay]]``),
  starting ``REPLAY_STRIDE_S`` x seed into the file (each seed another stretch of the
  recording); the robot crosses the tracks' x span at their median y, from 1 m inside one
  end to 1 m inside the other, with no walls (the benchmarks' recordings are of open
  places). The packaged file (``worlds/tracks/walkers-hall.txt``, made by
  :mod:`papf.experiments.crowd_tracks`) was recorded in the hall: its scene is the hall's
  (walls, start and goal).

Every scene is returned with its TOML, so ``papf plan --world OUT/worlds/<name>.toml``
repeats a run.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from common.errors import ConfigError
from common.optional import tomllib
from worlds import World, parse_world

HALL_X = (-1.5, 9.5)          # [m] the hall's walls along x
HALL_Y = (-3.0, 3.0)          # [m] along y
START, GOAL = (0.0, 0.0, 0.0), (8.0, 0.0)
SPEED_M_S = (0.5, 1.0)        # [m/s] preferred speeds drawn from
CLEAR_M = 0.7                 # [m] between the centres of drawn points and the robot's ends
MARGIN_M = 0.6                # [m] a person's start/goal from the walls
MAX_HALL_PEOPLE = 20          # [-] the strips hold this many at CLEAR_M for every seed tried (0-59)


def _draw_point(rng, kind: str, end: int, taken: list) -> tuple[float, float]:
    """A start (end 0) or goal (end 1) of a walker ``along`` or ``across`` the hall."""
    (x0, x1), (y0, y1) = HALL_X, HALL_Y
    for _ in range(1000):
        if kind == "along":
            x = rng.uniform(x1 - MARGIN_M - 2.0, x1 - MARGIN_M) if end == 0 else \
                rng.uniform(x0 + MARGIN_M, x0 + MARGIN_M + 2.0)
            y = rng.uniform(y0 + MARGIN_M, y1 - MARGIN_M)
        else:
            x = rng.uniform(x0 + 2.0, x1 - 2.0)
            side = y0 + MARGIN_M if end == 0 else y1 - MARGIN_M
            y = side + rng.uniform(0.0, 1.2) * (1 if end == 0 else -1)
        if all(math.hypot(x - a, y - b) >= CLEAR_M for a, b in taken):
            return round(float(x), 3), round(float(y), 3)
    raise ConfigError(f"no room left in the hall for a walker {kind} it after "
                      f"{len(taken) // 2 - 1} people")


def crowd_scene(people: int, seed: int) -> tuple[World, str]:
    """The hall with ``people`` pedestrians of ``seed`` (module doc): (world, its TOML)."""
    if not 0 <= people <= MAX_HALL_PEOPLE:
        raise ConfigError(f"{people} people: the hall takes 0 to {MAX_HALL_PEOPLE}")
    rng = np.random.default_rng([seed, people])
    taken = [START[:2], GOAL]
    lines = []
    for k in range(people):
        kind = "along" if k % 2 == 0 else "across"
        flip = rng.random() < 0.5                     # which end or wall they start from
        a = _draw_point(rng, kind, 1 if flip else 0, taken)
        taken.append(a)
        b = _draw_point(rng, kind, 0 if flip else 1, taken)
        taken.append(b)
        speed = round(float(rng.uniform(*SPEED_M_S)), 3)
        lines += ["[[people]]", f"start = [{a[0]}, {a[1]}]",
                  f"waypoints = [[{b[0]}, {b[1]}], [{a[0]}, {a[1]}]]", "loop = true",
                  f"speed = {speed}"]
    (x0, x1), (y0, y1) = HALL_X, HALL_Y
    name = f"crowd-{people}-{seed}"
    head = [f'name = "{name}"',
            f'description = "a {x1 - x0:g} x {y1 - y0:g} m hall, {people} people walking back '
            f'and forth (papf experiment crowd, seed {seed})"',
            "[robot]", f"start = {list(START)}", "[goal]", f"position = {list(GOAL)}",
            "tolerance = 0.1"]
    for a, b in (((x0, y0), (x1, y0)), ((x0, y1), (x1, y1)), ((x0, y0), (x0, y1)),
                 ((x1, y0), (x1, y1))):
        head += ["[[obstacles]]", 'kind = "wall"', f"from = {list(a)}", f"to = {list(b)}",
                 "thickness = 0.1"]
    text = "\n".join(head + lines) + "\n"
    return parse_world(tomllib.loads(text), f"{name}.toml"), text


GROUPS_SALT = 7001
STANDING_GROUPS = 2
GROUP_RING_M = 0.45          # [m] a standing member's distance from the group's centre
REPLAY_STRIDE_S = 20.0       # [s] between two seeds' starts in a track file
PERSON_R = 0.25              # [m] radius of the scenes' people (the replay default)
PACKAGED_TRACKS = "walkers-hall.txt"


def _hall_head(name: str, description: str, hall, start, goal, walls: bool = True) -> list:
    head = [f'name = "{name}"', f'description = "{description}"', "[robot]",
            f"start = {list(start)}", "[goal]", f"position = {list(goal)}", "tolerance = 0.1"]
    if walls:
        (x0, x1), (y0, y1) = hall
        for a, b in (((x0, y0), (x1, y0)), ((x0, y1), (x1, y1)), ((x0, y0), (x0, y1)),
                     ((x1, y0), (x1, y1))):
            head += ["[[obstacles]]", 'kind = "wall"', f"from = {list(a)}", f"to = {list(b)}",
                     "thickness = 0.1"]
    return head


def _free(x: float, y: float, taken: list, clear: float) -> bool:
    return all(math.hypot(x - a, y - b) >= clear for a, b in taken)


def _group_centre(rng, first: bool, taken: list) -> tuple[float, float]:
    for _ in range(1000):
        x = rng.uniform(2.5, 5.5) if first else rng.uniform(1.0, 7.0)
        y = rng.uniform(-0.6, 0.6) if first else rng.uniform(-2.0, 2.0)
        if _free(x, y, taken, 1.6):
            return round(float(x), 3), round(float(y), 3)
    raise ConfigError("no room left in the hall for a standing group")


def groups_scene(seed: int) -> tuple[World, str]:
    """The hall with standing groups, standing people and a walking pair (module doc)."""
    rng = np.random.default_rng([seed, GROUPS_SALT])
    taken: list = [START[:2], GOAL]
    people: list[list[str]] = []
    groups: list[list[int]] = []
    for g in range(STANDING_GROUPS):
        cx, cy = _group_centre(rng, g == 0, taken)
        taken.append((cx, cy))
        turn = rng.uniform(0, 2 * math.pi)
        members = []
        for k in range(3):
            a = turn + k * 2 * math.pi / 3
            members.append(len(people))
            people.append([f"start = [{cx + GROUP_RING_M * math.cos(a):.3f}, "
                           f"{cy + GROUP_RING_M * math.sin(a):.3f}]", "speed = 0.0"])
        groups.append(members)
    for _ in range(2):                                   # standing alone
        for _ in range(1000):
            x, y = rng.uniform(1.0, 7.0), rng.uniform(-2.2, 2.2)
            if _free(x, y, taken, 1.2):
                break
        taken.append((x, y))
        people.append([f"start = [{x:.3f}, {y:.3f}]"])
    x = round(float(rng.uniform(1.5, 6.5)), 3)           # a pair walking across and back
    groups.append([len(people), len(people) + 1])
    for dx in (0.0, 0.7):
        a, b = (x + dx, HALL_Y[0] + 0.6), (x + dx, HALL_Y[1] - 0.6)
        people.append([f"start = [{a[0]}, {a[1]}]", f"waypoints = [[{b[0]}, {b[1]}], "
                       f"[{a[0]}, {a[1]}]]", "loop = true", "speed = 0.8"])
    for k in range(4):                                   # walkers, as the hall's
        kind = "along" if k % 2 == 0 else "across"
        a = _draw_point(rng, kind, 0, taken)
        taken.append(a)
        b = _draw_point(rng, kind, 1, taken)
        taken.append(b)
        people.append([f"start = [{a[0]}, {a[1]}]", f"waypoints = [[{b[0]}, {b[1]}], "
                       f"[{a[0]}, {a[1]}]]", "loop = true",
                       f"speed = {round(float(rng.uniform(0.5, 1.0)), 3)}"])
    name = f"crowd-groups-{seed}"
    lines = _hall_head(name, f"two groups of three standing, two people standing, a pair and "
                       f"four walkers (papf experiment crowd, seed {seed})", (HALL_X, HALL_Y),
                       START, GOAL)
    for p in people:
        lines += ["[[people]]", *p, f"radius = {PERSON_R}"]
    for members in groups:
        lines += ["[[groups]]", f"members = {members}"]
    text = "\n".join(lines) + "\n"
    return parse_world(tomllib.loads(text), f"{name}.toml"), text


def replay_scene(track_file: str | Path, seed: int) -> tuple[World, str]:
    """``track_file`` replayed from ``REPLAY_STRIDE_S`` x ``seed`` s (module doc)."""
    path = Path(track_file).resolve()
    stem = path.stem.replace(" ", "_")[:40]
    name = f"crowd-replay-{stem}-{seed}"
    replay = ["[[people_replay]]", f"file = {_toml_str(str(path))}", 'format = "eth-ucy"',
              f"from_s = {REPLAY_STRIDE_S * seed:.1f}", f"radius = {PERSON_R}"]
    desc = f"{path.name} replayed from {REPLAY_STRIDE_S * seed:g} s (papf experiment crowd)"
    if path.name == PACKAGED_TRACKS:                     # the hall's own recording
        lines = _hall_head(name, desc, (HALL_X, HALL_Y), START, GOAL)
    else:
        (x0, x1), ym = _bounds(path)
        lines = _hall_head(name, desc, None, (round(x0 + 1, 3), ym, 0.0),
                           (round(x1 - 1, 3), ym), walls=False)
    text = "\n".join(lines + replay) + "\n"
    return parse_world(tomllib.loads(text), f"{name}.toml"), text


def _bounds(path: Path) -> tuple[tuple[float, float], float]:
    """The x span of a track file's positions and the middle of its y span [m]."""
    rows = parse_world(tomllib.loads(f'[goal]\nposition = [0.0, 0.0]\n[[people_replay]]\n'
                                     f'file = {_toml_str(str(path))}\n'), "bounds.toml")
    xy = np.array([p for tr in rows.replayed for p in tr.xy])
    if not len(xy) or xy[:, 0].max() - xy[:, 0].min() < 3.0:
        raise ConfigError(f"{path}: its tracks span less than 3 m along x; the robot crosses "
                          "a replayed scene along x")
    return (float(xy[:, 0].min()), float(xy[:, 0].max())), round(float(np.median(xy[:, 1])), 3)


def _toml_str(s: str) -> str:
    """A TOML basic string."""
    return '"' + s.replace("\\", "\\\\").replace('"', '\\"') + '"'


def packaged_tracks() -> Path:
    """The packaged recording (``worlds/tracks/walkers-hall.txt``)."""
    import worlds

    return Path(worlds.__file__).parent / "tracks" / PACKAGED_TRACKS
