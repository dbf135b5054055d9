"""What a world file may contain, checked before it is read into a World (docs/worlds.md "Limits").

A misspelt key is not ignored: ``hieght = 2.0`` on an obstacle or a ``[mapp]`` table would
give a run in another world than the one the user wrote, so every key must be one the format
knows — a WorldError names the entry and the closest valid key ("did you mean"). And every
size a world can ask the stack to allocate or loop over is bounded, so a hostile file fails
at once, in one line, before any process starts:

- the file itself: :data:`MAX_FILE_BYTES` (read no further), TOML nesting :data:`MAX_DEPTH`;
- strings: a name of :data:`MAX_NAME_CHARS`, a description of :data:`MAX_DESCRIPTION_CHARS`;
- ``[road] lanes`` up to :data:`MAX_LANES`, a motion track of :data:`MAX_TRACK_POINTS`,
  :data:`MAX_OBSTACLES` obstacles.

The key tables are data (:data:`TOP`, :data:`TABLES`); an obstacle kind declares its own keys
(``Kind.keys``, :mod:`worlds.kinds`), and a kind with a table of its own (``[map]``) adds it.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable

from common.errors import WorldError
from worlds.fleet import GROUP_KEYS, PERSON_KEYS, ROBOT_KEYS
from worlds.kinds import KINDS
from worlds.people_replay import REPLAY_KEYS

MAX_FILE_BYTES = 1024 * 1024     # [bytes] the largest packaged world is 3 KB
MAX_DEPTH = 6                    # [-] tables/arrays nested (obstacles[].motion.track[][] is 5)
MAX_NAME_CHARS = 100             # [chars]
MAX_DESCRIPTION_CHARS = 4000     # [chars]
MAX_LANES = 16                   # [-] a motorway has 4-5 per direction
MAX_TRACK_POINTS = 10_000        # [-] samples of one obstacle's motion track
MAX_OBSTACLES = 10_000           # [-] in a file

TOP = ("name", "description", "robot", "goal", "obstacles", "road", "robots", "people", "groups",
       "people_replay")
TABLES = {"robot": ("start", "vehicle"), "goal": ("position", "tolerance"),
          "road": ("y_min", "lane_width", "lanes")}
MOTION_KEYS = ("track",)


def _tables() -> dict[str, tuple]:
    """:data:`TABLES` and the tables of the kinds that have their own (``[map]``)."""
    return {**TABLES, **{k.name: k.keys for k in KINDS.values() if not k.listed}}


def check_text_size(size: int, source: str) -> None:
    """A world file of ``size`` bytes may be read."""
    if size > MAX_FILE_BYTES:
        raise WorldError(f"world {source!r}: {size:,} bytes, more than the {MAX_FILE_BYTES:,} a "
                         "world file may have")


def check_document(data: dict, source: str) -> None:
    """Every key known, every size within its limit (module doc); WorldError otherwise."""
    _depth(data, source)
    tables = _tables()
    _keys(data, (*TOP, *(t for t in tables if t not in TOP)), "", source)
    for table, valid in tables.items():
        if isinstance(data.get(table), dict):
            _keys(data[table], valid, f"[{table}]", source)
    for key, limit in (("name", MAX_NAME_CHARS), ("description", MAX_DESCRIPTION_CHARS)):
        value = data.get(key)
        if isinstance(value, str) and len(value) > limit:
            _fail(source, key, f"{len(value):,} characters, more than {limit:,}")
    road = data.get("road")
    lanes = road.get("lanes") if isinstance(road, dict) else None
    if isinstance(lanes, int) and not isinstance(lanes, bool) and lanes > MAX_LANES:
        _fail(source, "road.lanes", f"{lanes} lanes, more than {MAX_LANES}")
    _obstacles(data.get("obstacles"), source)
    for array, valid in (("robots", ROBOT_KEYS), ("people", PERSON_KEYS), ("groups", GROUP_KEYS),
                         ("people_replay", REPLAY_KEYS)):
        entries = data.get(array)
        for i, entry in enumerate(entries if isinstance(entries, list) else ()):
            if isinstance(entry, dict):
                _keys(entry, valid, f"{array}[{i}]", source)


def _obstacles(raw, source: str) -> None:
    if not isinstance(raw, list):
        return   # the parser says what an obstacles entry must be
    if len(raw) > MAX_OBSTACLES:
        _fail(source, "obstacles", f"{len(raw):,} obstacles, more than {MAX_OBSTACLES:,}")
    for i, ob in enumerate(raw):
        if not isinstance(ob, dict):
            continue
        where = f"obstacles[{i}]"
        kind = KINDS.get(ob.get("kind")) if isinstance(ob.get("kind"), str) else None
        if kind is not None and kind.listed:
            _keys(ob, ("kind", *kind.keys), where, source, f"a {kind.name}")
        motion = ob.get("motion")
        if isinstance(motion, dict):
            _keys(motion, MOTION_KEYS, f"{where}.motion", source)
            track = motion.get("track")
            if isinstance(track, list) and len(track) > MAX_TRACK_POINTS:
                _fail(source, f"{where}.motion.track",
                      f"{len(track):,} points, more than {MAX_TRACK_POINTS:,}")


def _keys(table: dict, valid: Iterable[str], where: str, source: str, what: str = "") -> None:
    valid = tuple(valid)
    for key in table:
        if key in valid:
            continue
        close = difflib.get_close_matches(str(key), valid, n=1, cutoff=0.6)
        hint = f"; did you mean {close[0]!r}?" if close else ""
        place = f"{where}.{key}" if where and not where.startswith("[") else \
            f"{where} {key}" if where else f"[{key}]" if isinstance(table[key], dict) else key
        has = f"{what} has" if what else "valid"
        _fail(source, place, f"unknown key{hint} ({has}: {', '.join(valid)})")


def _depth(node, source: str) -> None:
    """Nesting of tables and arrays within :data:`MAX_DEPTH` (iterative: no recursion)."""
    stack = [(node, 0)]
    while stack:
        item, depth = stack.pop()
        if depth > MAX_DEPTH:
            _fail(source, "(file)", f"tables or arrays nested deeper than {MAX_DEPTH}")
        if isinstance(item, dict):
            stack.extend((v, depth + 1) for v in item.values() if isinstance(v, (dict, list)))
        elif isinstance(item, list):
            stack.extend((v, depth + 1) for v in item if isinstance(v, (dict, list)))


def _fail(source: str, where: str, problem: str):
    shown = source if len(source) <= 200 else source[:197] + "..."
    raise WorldError(f"world {shown!r}: {where}: {problem}")
