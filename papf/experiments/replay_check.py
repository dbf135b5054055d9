"""Where a recording's replayed people are against their track file, checked independently.

``python -m papf.experiments.replay_check RUN.mcap TRACKS.txt FROM_S [--fps 25] [--csv F]``:
reads the ``eth-ucy`` rows (``frame id x y``) with its own parser and its own linear
interpolation (not :mod:`worlds.people_replay`, which put them there), and compares every
``<ns>/sim/people`` message of the recording with the file at run time + ``FROM_S``: the
worst distance, and that every person absent from the file at that instant has radius 0.
Used for the real ETH recording in docs/experiments.md ("Real people: the ETH recording").
Assumes the world's ``offset`` is (0, 0) and the replay is the world's only people.
"""

from __future__ import annotations

import argparse
import csv
import itertools
import math
import sys
from pathlib import Path

from papf.recording.reader import iter_messages


def read_tracks(path: Path, fps: float, from_s: float) -> list[list[tuple[float, float, float]]]:
    """Each person's ``(t, x, y)`` in run time, in the order the stack keeps (first row, then
    the file's order); people gone before ``from_s`` are left out, as the stack does."""
    rows = [line.split() for line in path.read_text().splitlines() if line.strip()]
    frame0 = min(float(r[0]) for r in rows)
    tracks: dict[str, list] = {}
    for frame, pid, x, y in rows:
        tracks.setdefault(pid, []).append(((float(frame) - frame0) / fps - from_s,
                                           float(x), float(y)))
    kept = [tr for tr in tracks.values() if tr[-1][0] >= 0]
    return sorted(kept, key=lambda tr: tr[0][0])


def position(track, t: float) -> tuple[float, float] | None:
    """Linear between rows, None outside the first..last row."""
    if t < track[0][0] or t > track[-1][0]:
        return None
    for (t0, x0, y0), (t1, x1, y1) in itertools.pairwise(track):
        if t0 <= t <= t1:
            a = 0.0 if t1 == t0 else (t - t0) / (t1 - t0)
            return x0 + a * (x1 - x0), y0 + a * (y1 - y0)
    return track[-1][1], track[-1][2]


def check(rec: str, tracks, key: str = "rosbot/sim/people") -> dict:
    worst, messages, present, misplaced_absent = 0.0, 0, 0, 0
    for _key, msg, _t in iter_messages(rec, key):
        t = msg.stamp_ns / 1e9
        for k, tr in enumerate(tracks):
            p = position(tr, t)
            if p is None:
                misplaced_absent += msg.radius[k] != 0.0
                continue
            present += 1
            worst = max(worst, math.hypot(msg.x[k] - p[0], msg.y[k] - p[1]))
        messages += 1
    return {"messages": messages, "tracks": len(tracks), "person_instants": present,
            "worst_cm": round(worst * 100, 3), "absent_but_shown": misplaced_absent}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m papf.experiments.replay_check",
                                 description=__doc__.splitlines()[0])
    ap.add_argument("recording")
    ap.add_argument("tracks", type=Path)
    ap.add_argument("from_s", type=float)
    ap.add_argument("--fps", type=float, default=25.0)
    ap.add_argument("--csv", type=Path, help="append a row here")
    args = ap.parse_args(argv)
    row = {"recording": Path(args.recording).name, "tracks_file": args.tracks.name,
           "from_s": args.from_s, **check(args.recording, read_tracks(args.tracks, args.fps,
                                                                       args.from_s))}
    print(row)
    if args.csv:
        new = not args.csv.exists()
        with args.csv.open("a", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(row))
            if new:
                w.writeheader()
            w.writerow(row)
    return 0 if row["absent_but_shown"] == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
