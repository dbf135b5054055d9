"""Both sides of a split run: the laptop's recording and the robot's black box (docs/link-driving.md).

``papf launch robot --record F.mcap`` records on the robot (metadata ``profile=robot`` or
``hil-robot``) for as long as the robot side runs: one file may hold several runs, each
from the ``run_started`` it received to its ``run_ended`` (by the wall clock of the
robot's recorder). The laptop's recording holds one run, and misses whatever the link
did not carry. For a run recorded on both sides :func:`pair` says:

- which figures come from where: **path, duration, charge and energy from the robot**
  (its odometry and wheels reach its own recorder whatever the link does); outcome and
  reason from the laptop (the launcher judged the run there);
- which intervals of the robot's odometry the laptop's recording misses (its run clock).

A robot recording given alone is reported run by run like any other recording.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, replace
from pathlib import Path

from papf.recording.reader import Recording, decode
from papf.recording.rosbag import TopicMap, is_rosbag
from schemas import Event, Odometry

ROBOT_PROFILES = ("robot", "hil-robot")
END_TAIL_NS = 2_000_000_000   # [ns wall] messages of a run still arriving after its run_ended
MISSED_MIN_S = 0.1            # [s] a shorter hole in the laptop's odometry is not reported
TAKEN_FROM_ROBOT = ("path_length_m", "duration_s", "charge_mAh", "energy_J")


@dataclass(frozen=True)
class Segment:
    """One run in a robot recording: wall-clock receive times [ns] of its start and end."""

    index: int
    start_ns: int
    end_ns: int | None      # None: the recording ends before the run did
    ended: str              # the run_ended detail (the launcher's result as JSON), "" if none


def is_robot_side(path: Path, topics: TopicMap | None = None) -> bool:
    """A black box recorded by a robot launch profile."""
    if is_rosbag(path, topics):
        return False
    with Recording(path) as rec:
        return rec.run_metadata.get("profile") in ROBOT_PROFILES


def segments(path: Path) -> list[Segment]:
    """The runs a robot recording holds, in order."""
    out: list[Segment] = []
    start: int | None = None
    with Recording(path) as rec:
        keys = [k for k in rec.keys() if k.endswith("/events")]
        for raw in rec.raw(keys):
            msg = decode(raw.schema_name, raw.data)
            if not isinstance(msg, Event):
                continue
            if msg.kind == "run_started":
                if start is not None:
                    out.append(Segment(len(out), start, raw.publish_time_ns, ""))
                start = raw.publish_time_ns
            elif msg.kind == "run_ended" and start is not None:
                out.append(Segment(len(out), start, raw.publish_time_ns + END_TAIL_NS, msg.detail))
                start = None
    if start is not None:
        out.append(Segment(len(out), start, None, ""))
    return out


def run_ended_detail(path: Path) -> str:
    """The run_ended detail a laptop recording holds ('' if none)."""
    with Recording(path) as rec:
        keys = [k for k in rec.keys() if k.endswith("/events")]
        for _key, msg, _t in rec.messages(keys):
            if isinstance(msg, Event) and msg.kind == "run_ended":
                return msg.detail
    return ""


def odom_stamps(path: Path, ns: str, window: Segment | None = None) -> list[int]:
    """Stamps [ns, run clock] of ``<ns>/odom`` (within a robot segment's wall window)."""
    out = []
    with Recording(path) as rec:
        for raw in rec.raw([f"{ns}/odom"]):
            if window is not None and not in_window(raw.publish_time_ns, window):
                continue
            msg = decode(raw.schema_name, raw.data)
            if isinstance(msg, Odometry):
                out.append(msg.stamp_ns)
    return out


def in_window(wall_ns: int, seg: Segment) -> bool:
    return wall_ns >= seg.start_ns and (seg.end_ns is None or wall_ns <= seg.end_ns)


def missed(laptop: list[int], robot: list[int], t_end_ns: int) -> list[tuple[float, float]]:
    """Intervals [s] of the robot's odometry (up to ``t_end_ns``) the laptop does not hold:
    consecutive robot samples absent from the laptop's, at least MISSED_MIN_S long."""
    have = set(laptop)
    out, first, last = [], None, None
    for t in sorted(s for s in robot if s <= t_end_ns):
        if t in have:
            if first is not None:
                out.append((first, last))
            first = None
            continue
        first = t if first is None else first
        last = t
    if first is not None:
        out.append((first, last))
    return [(a / 1e9, b / 1e9) for a, b in out if (b - a) / 1e9 >= MISSED_MIN_S]


def match(laptop_ended: str, segs: list[Segment]) -> Segment | None:
    """The robot segment of a laptop run: the same run_ended (the launcher's result), else
    the one robot run when there is exactly one."""
    if laptop_ended:
        same = [s for s in segs if s.ended == laptop_ended]
        if same:
            return same[0]
    return segs[0] if len(segs) == 1 else None


def pair(laptop, robot, missed_s: list[tuple[float, float]], robot_file: str):
    """The laptop's run with the robot's figures where the robot knows better, and
    ``sides``: which figure came from where, both values, the laptop's missed intervals."""
    sides = {"robot_file": robot_file, "laptop_file": laptop.file,
             "taken_from_robot": list(TAKEN_FROM_ROBOT),
             "taken_from_laptop": ["outcome", "reason", "live_charge_mAh"],
             "laptop": {k: getattr(laptop, k) for k in TAKEN_FROM_ROBOT},
             "robot": {k: getattr(robot, k) for k in TAKEN_FROM_ROBOT},
             "laptop_missed_s": [[round(a, 3), round(b, 3)] for a, b in missed_s],
             "laptop_missed_total_s": round(sum(b - a for a, b in missed_s), 3)}
    merged = replace(laptop, **{k: getattr(robot, k) for k in TAKEN_FROM_ROBOT},
                     series=robot.series or laptop.series)
    merged.sides = sides
    return merged


def sides_markdown(runs) -> str:
    """The report's table of runs recorded on both sides."""
    lines = ["| run | figure | laptop | robot (used) |", "|---|---|---|---|"]
    for r in runs:
        s = r.sides
        for k in TAKEN_FROM_ROBOT:
            lines.append(f"| {r.file} | {k} | {_num(s['laptop'][k])} | {_num(s['robot'][k])} |")
        holes = ", ".join(f"{a:.2f}–{b:.2f} s" for a, b in s["laptop_missed_s"]) or "none"
        lines.append(f"| {r.file} | laptop missed | {holes} | ({s['robot_file']}) |")
    return "\n".join(lines)


def _num(x) -> str:
    return "—" if x is None or x != x else f"{x:.3f}"


def result_of(ended: str) -> dict:
    try:
        out = json.loads(ended)
    except ValueError:
        return {}
    return out if isinstance(out, dict) else {}
