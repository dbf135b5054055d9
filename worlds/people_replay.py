"""Real people, replayed as recorded: ``[[people_replay]]`` (docs/worlds.md).

A replay entry names a track file in the form the trajectory-prediction benchmarks ship the
ETH (Pellegrini et al. 2009, "You'll never walk alone") and UCY (Lerner et al. 2007, "Crowds
by example") recordings in (format ``eth-ucy``): one row per person and frame, ``frame id x
y``, whitespace-separated, x and y in metres. The people of the file do not react to anyone:
each is in the world from its first row to its last, linearly interpolated between rows
(:func:`replay_state`).

Time: a row's file time is ``(frame - first frame of the file) / fps``; run time ``t`` shows
the file at ``from_s + t``. People whose last row lies before ``from_s`` never appear and
are dropped; the others keep the order of their first row (then of their id).

The loader is strict (a bad file must not give a run in another scene than the user's): an
unknown format, a missing or unreadable file, a row that is not four finite numbers, a
person's frame that does not increase, coordinates beyond the world's span - each a
WorldError naming the file and the line. Sizes are bounded (:data:`MAX_FILE_BYTES`,
:data:`MAX_ROWS`, :data:`MAX_REPLAY_PEOPLE`).
"""

from __future__ import annotations

import math
from bisect import bisect_right
from dataclasses import dataclass
from pathlib import Path

REPLAY_KEYS = ("file", "format", "fps", "from_s", "offset", "radius")
REPLAY_FORMATS = ("eth-ucy",)
DEFAULT_FPS = 25.0               # [1/s] the ETH/UCY frame numbers' rate (frames step by 10 at 2.5 Hz)
REPLAY_RADIUS_M = 0.25           # [m] default body radius of a replayed person
MAX_REPLAY_FILES = 8             # [-] replay entries in one world
MAX_FILE_BYTES = 32 * 1024 * 1024   # [bytes] the largest ETH/UCY file (univ) is under 1 MB
MAX_ROWS = 500_000               # [-] rows of one file
MAX_REPLAY_PEOPLE = 2000         # [-] replayed people in one world (ETH's eth: 360)
MAX_FPS = 1000.0                 # [1/s]


@dataclass(frozen=True)
class ReplayTrack:
    """One recorded person: run times [s] (increasing) and positions [m] in the world frame."""

    id: str                                 # the file's person id, as written
    times: tuple[float, ...]                # [s] run time of each row
    xy: tuple[tuple[float, float], ...]     # [m] world frame (offset applied)

    @property
    def first_s(self) -> float:
        return self.times[0]

    @property
    def last_s(self) -> float:
        return self.times[-1]


@dataclass(frozen=True)
class ReplaySpec:
    """One ``[[people_replay]]`` entry, its file read."""

    file: str                               # as written in the world (relative to it)
    path: str                               # resolved path that was read
    format: str = "eth-ucy"
    fps: float = DEFAULT_FPS
    from_s: float = 0.0
    offset: tuple[float, float] = (0.0, 0.0)
    radius: float = REPLAY_RADIUS_M
    tracks: tuple[ReplayTrack, ...] = ()


def replay_state(track: ReplayTrack, t_s: float) -> tuple[float, float, float, float] | None:
    """(x, y, vx, vy) [m, m/s] of ``track`` at run time ``t_s``, linear between rows; None
    before its first row and after its last (not in the scene)."""
    times = track.times
    if not times[0] <= t_s <= times[-1]:
        return None
    k = bisect_right(times, t_s) - 1
    if k >= len(times) - 1:                 # exactly at the last row: hold, the last leg's speed
        k = max(len(times) - 2, 0)
        if len(times) == 1:
            return (*track.xy[0], 0.0, 0.0)
    (x0, y0), (x1, y1) = track.xy[k], track.xy[k + 1]
    dt = times[k + 1] - times[k]
    a = min(max((t_s - times[k]) / dt, 0.0), 1.0)
    return x0 + a * (x1 - x0), y0 + a * (y1 - y0), (x1 - x0) / dt, (y1 - y0) / dt


def parse_replays(ctx, raw, source: str, max_coord_m: float) -> tuple[ReplaySpec, ...]:
    """``[[people_replay]]`` -> specs, each file read (``ctx``: the world parser's field
    reader; paths relative to the world file ``source``; positions within ``max_coord_m``)."""
    if not isinstance(raw, list) or not raw:
        ctx.fail("people_replay", "must be a non-empty array of tables ([[people_replay]])")
    if len(raw) > MAX_REPLAY_FILES:
        ctx.fail("people_replay", f"{len(raw)} entries, more than {MAX_REPLAY_FILES}")
    out, total = [], 0
    for i, t in enumerate(raw):
        where = f"people_replay[{i}]"
        if not isinstance(t, dict):
            ctx.fail(where, "must be a table")
        spec = _parse_one(ctx, t, where, source, max_coord_m)
        total += len(spec.tracks)
        if total > MAX_REPLAY_PEOPLE:
            ctx.fail(where, f"{total} replayed people, more than {MAX_REPLAY_PEOPLE}")
        out.append(spec)
    return tuple(out)


def _parse_one(ctx, t: dict, where: str, source: str, max_coord_m: float) -> ReplaySpec:
    fmt = ctx.str(t, "format", f"{where}.format", default="eth-ucy")
    if fmt not in REPLAY_FORMATS:
        ctx.fail(f"{where}.format", f"{fmt!r} is not a known track format (known: "
                 f"{', '.join(REPLAY_FORMATS)})")
    file = ctx.str(t, "file", f"{where}.file")
    fps = ctx.positive(t, "fps", f"{where}.fps", default=DEFAULT_FPS)
    if fps > MAX_FPS:
        ctx.fail(f"{where}.fps", f"{fps:g} frames per second; valid: (0, {MAX_FPS:g}]")
    from_s = ctx.number(t, "from_s", f"{where}.from_s", default=0.0)
    if from_s < 0:
        ctx.fail(f"{where}.from_s", f"must be >= 0 s (a time after the file's first row), "
                 f"got {from_s:g}")
    offset = tuple(ctx.vec(t, "offset", (2,), f"{where}.offset", default=[0.0, 0.0]))
    radius = ctx.positive(t, "radius", f"{where}.radius", default=REPLAY_RADIUS_M)
    from worlds.fleet import MAX_PERSON_RADIUS_M

    if radius > MAX_PERSON_RADIUS_M:
        ctx.fail(f"{where}.radius", f"{radius:g} m is wider than a person "
                 f"(valid: (0, {MAX_PERSON_RADIUS_M:g}] m)")
    path = _resolve(file, source)
    rows = read_eth_ucy(ctx, path, f"{where}.file")
    tracks = _tracks(ctx, rows, fps, from_s, offset, path, max_coord_m)
    return ReplaySpec(file=file, path=str(path), format=fmt, fps=fps, from_s=from_s,
                      offset=offset, radius=radius, tracks=tracks)


def _resolve(file: str, source: str) -> Path:
    """``file`` relative to the world file's folder (as ``[map]``'s), unless absolute."""
    p = Path(file).expanduser()
    if p.is_absolute():
        return p
    base = Path(source).parent if source and not source.startswith("<") else Path(".")
    return base / p


def read_eth_ucy(ctx, path: Path, where: str) -> list[tuple[int, float, str, float, float]]:
    """The rows of an ``eth-ucy`` file: (line number, frame, id, x, y); blank lines skipped."""
    shown = str(path)
    if not path.is_file():
        ctx.fail(where, f"track file {shown!r} does not exist (a path relative to the world file)")
    try:
        size = path.stat().st_size
        if size > MAX_FILE_BYTES:
            ctx.fail(where, f"track file {shown!r}: {size:,} bytes, more than the "
                     f"{MAX_FILE_BYTES:,} a track file may have")
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        ctx.fail(where, f"cannot read track file {shown!r}: {exc}")
    rows = []
    for n, line in enumerate(text.splitlines(), start=1):
        fields = line.split()
        if not fields:
            continue
        if len(rows) >= MAX_ROWS:
            ctx.fail(where, f"track file {shown!r}: more than {MAX_ROWS:,} rows")
        rows.append((n, *_row(ctx, fields, shown, n, where)))
    if not rows:
        ctx.fail(where, f"track file {shown!r} has no rows (expected 'frame id x y' per line)")
    return rows


def _row(ctx, fields: list[str], shown: str, n: int, where: str):
    """One row's (frame, id, x, y); WorldError naming file and line otherwise."""
    line = " ".join(fields)
    if len(fields) != 4:
        ctx.fail(where, f"{shown}:{n}: expected 4 columns 'frame id x y', got {len(fields)}: "
                 f"{line[:80]!r}")
    try:
        frame, pid, x, y = (float(v) for v in fields)
    except ValueError:
        ctx.fail(where, f"{shown}:{n}: 'frame id x y' must be numbers, got {line[:80]!r}")
    if not all(math.isfinite(v) for v in (frame, pid, x, y)):
        ctx.fail(where, f"{shown}:{n}: a value is not finite: {line[:80]!r}")
    return frame, fields[1], x, y


def _tracks(ctx, rows, fps: float, from_s: float, offset, path: Path,
            max_coord_m: float) -> tuple[ReplayTrack, ...]:
    """Rows -> one track per id in run time (module doc), frames strictly increasing per id."""
    frame0 = min(r[1] for r in rows)
    by_id: dict[str, list] = {}
    for n, frame, pid, x, y in rows:
        key = _plain_id(pid)
        mine = by_id.setdefault(key, [])
        if mine and frame <= mine[-1][1]:
            ctx.fail("people_replay", f"{path}:{n}: person {pid} at frame {frame:g} after frame "
                     f"{mine[-1][1]:g} (each person's frames must increase)")
        wx, wy = x + offset[0], y + offset[1]
        if abs(wx) > max_coord_m or abs(wy) > max_coord_m:
            ctx.fail("people_replay", f"{path}:{n}: ({wx:g}, {wy:g}) is beyond the "
                     f"{max_coord_m:g} m a world may span")
        mine.append((n, frame, wx, wy))
    tracks = []
    for key, mine in by_id.items():
        times = tuple((f - frame0) / fps - from_s for _, f, _, _ in mine)
        if times[-1] < 0:
            continue                        # gone before the run starts
        tracks.append(ReplayTrack(id=key, times=times, xy=tuple((x, y) for *_, x, y in mine)))
    tracks.sort(key=lambda tr: tr.first_s)  # stable: ties keep the file's order
    return tuple(tracks)


def _plain_id(pid: str) -> str:
    """``1.0`` and ``1`` are the same person (the benchmarks write ids as floats)."""
    v = float(pid)
    return str(int(v)) if v.is_integer() else pid
