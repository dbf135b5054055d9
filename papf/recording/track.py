"""A recorded run as arrays for pictures (``papf animate``, the report's mind figure).

Poses from ground truth (``sim/pose``) when recorded, else odometry; speed from odometry;
charge from ``battery`` (a rosbag2 has none: re-metered from its odometry with the motor
model, as ``papf report`` does by default); every
``planner/state``. A fleet's recording: one robot's, and the others' ground-truth poses
and the people's positions (``sim/people``) beside them. Times in seconds of the
recording's stamps. Pure: reads the file,
nothing else.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from common.errors import ConfigError, PapfError
from nodes.energy_meter.core import EnergyMeter
from papf.recording.foxglove_export import stack_topic
from papf.recording.rosbag import NS, BagRecording, TopicMap, open_run
from schemas.messages import (
    BatteryState,
    BatteryVoltage,
    Odometry,
    People,
    PlannerState,
    Scan,
    WheelStates,
)
from worlds import World, load_world


@dataclass
class RunTrack:
    """What a picture of a run needs, from a recording (times [s])."""

    world: World | None
    title: str
    t: np.ndarray = field(default_factory=lambda: np.zeros(0))      # pose times
    xyyaw: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    v_t: np.ndarray = field(default_factory=lambda: np.zeros(0))    # odometry times
    v: np.ndarray = field(default_factory=lambda: np.zeros(0))      # [m/s]
    q_t: np.ndarray = field(default_factory=lambda: np.zeros(0))    # battery times
    q: np.ndarray = field(default_factory=lambda: np.zeros(0))      # [mAh]
    states: list[PlannerState] = field(default_factory=list)
    state_t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    scan_t: np.ndarray = field(default_factory=lambda: np.zeros(0))  # LiDAR scan times
    scans: list[np.ndarray] = field(default_factory=list)   # (n, 2) [m]: angle [rad], range
    # a fleet's other robots: name -> (times [s], (n, 3) x, y, yaw); the people's discs
    others: dict = field(default_factory=dict)
    people_t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    people_xy: list[np.ndarray] = field(default_factory=list)   # (k, 2) [m] per sample
    people_r: np.ndarray = field(default_factory=lambda: np.zeros(0))   # (k,) [m]
    # (k,) [m] per sample: a replayed person not in the scene then has radius 0
    people_radii: list[np.ndarray] = field(default_factory=list)


def scan_points(scan: Scan) -> np.ndarray:
    """(n, 2) bearing [rad, robot frame] and range [m] of a scan's finite readings."""
    r = np.asarray(scan.ranges, dtype=float)
    a = scan.angle_min + scan.angle_increment * np.arange(r.size)
    ok = np.isfinite(r) & (r >= scan.range_min) & (r <= scan.range_max)
    return np.column_stack([a[ok], r[ok]])


BAG_KEYS = [f"{NS}/odom", f"{NS}/wheels", f"{NS}/battery/measured"]


def _metered(meter: EnergyMeter, msg) -> list[BatteryState]:
    """What the energy meter says after ``msg`` (odometry, wheels or the measured voltage)."""
    try:
        if isinstance(msg, BatteryVoltage):
            meter.set_measured_voltage(msg.voltage, msg.stamp_ns)
            return []
        state = meter.feed(msg) if isinstance(msg, Odometry | WheelStates) else None
    except PapfError:   # a sample the meter refuses, as papf report's re-meter drops it
        return []
    return [state] if state is not None else []


def _fleet_sample(key: str, topic: str | None, msg, mine: str | None,
                  others: dict[str, list[Odometry]], people: list[People]) -> bool:
    """Keep ``msg`` if it is the people's or another robot's (True: it is not this robot's)."""
    if topic == "sim/people" and isinstance(msg, People):
        people.append(msg)
        return True
    ns = key[: -len(topic) - 1] if topic else ""
    if not (mine and ns and ns != mine):
        return False
    if topic == "sim/pose" and isinstance(msg, Odometry):   # another robot of a fleet
        others.setdefault(ns, []).append(msg)
    return True


def load_track(path: str | Path, world: str | None = None,
               topics: TopicMap | None = None, robot: str | None = None) -> RunTrack:
    """Poses (ground truth if recorded, else odometry), speed, charge, planner states of the
    recording's robot (a fleet's: ``robot``, else the recorder's namespace, its first); the
    other robots' ground-truth poses and the people's positions beside them."""
    poses: dict[str, list[Odometry]] = {"sim/pose": [], "odom": []}
    batt: list[BatteryState] = []
    states: list[PlannerState] = []
    scans: list[Scan] = []
    others: dict[str, list[Odometry]] = {}
    people: list[People] = []
    with open_run(path, topics) as rec:
        meta = rec.run_metadata
        bag = isinstance(rec, BagRecording)
        meter = EnergyMeter() if bag else None   # a bag has no meter's figures: re-meter it
        mine = robot or meta.get("namespace")
        for key, msg, _ in rec.messages(BAG_KEYS if bag else None):
            topic = stack_topic(key)
            if not bag and _fleet_sample(key, topic, msg, mine, others, people):
                continue
            if meter is not None:
                batt += _metered(meter, msg)
            if topic in poses and isinstance(msg, Odometry):
                poses[topic].append(msg)
            elif topic == "battery" and isinstance(msg, BatteryState):
                batt.append(msg)
            elif topic == "planner/state" and isinstance(msg, PlannerState):
                states.append(msg)
            elif topic == "scan" and isinstance(msg, Scan):
                scans.append(msg)
    name = world or (None if bag else meta.get("world"))
    w = None
    if name:
        try:
            w = load_world(name)
        except PapfError:
            if world:
                raise
    src = poses["sim/pose"] or poses["odom"]
    if not src:
        raise ConfigError(f"{path}: no sim/pose or odom messages to animate")
    odom = poses["odom"] or src
    return RunTrack(
        world=w, title=f"{meta.get('planner', '?')} on {w.name if w else meta.get('world', '?')}"
                       + (f" (seed {meta['seed']})" if "seed" in meta else ""),
        t=np.array([m.stamp_ns for m in src]) / 1e9,
        xyyaw=np.array([(m.x, m.y, m.yaw) for m in src]),
        v_t=np.array([m.stamp_ns for m in odom]) / 1e9, v=np.array([m.v for m in odom]),
        q_t=np.array([b.stamp_ns for b in batt]) / 1e9,
        q=np.array([b.charge_used_mAh for b in batt]),
        states=states, state_t=np.array([s.stamp_ns for s in states]) / 1e9,
        scan_t=np.array([s.stamp_ns for s in scans]) / 1e9, scans=[scan_points(s) for s in scans],
        others={n: (np.array([m.stamp_ns for m in ms]) / 1e9,
                    np.array([(m.x, m.y, m.yaw) for m in ms])) for n, ms in sorted(others.items())},
        people_t=np.array([p.stamp_ns for p in people]) / 1e9,
        people_xy=[np.column_stack([p.x, p.y]).reshape(-1, 2) for p in people],
        people_r=np.array(people[0].radius if people else ()),
        people_radii=[np.asarray(p.radius, float) for p in people])
