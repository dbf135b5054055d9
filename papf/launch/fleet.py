"""A fleet's run (``[[robots]]``): one :class:`RunSequence` per robot namespace, one result.

Each robot is judged on its own, from ground truth, by its own
:class:`~papf.launch.outcome.RunMonitor` (its goal, its ``sim/pose``, its planner's
statuses, its collisions). A robot that reached its goal stops (its planner answers every
scan with a stop) and stays an obstacle for the others; the run goes on until every robot
has an outcome. The fleet's figures (docs/architecture.md "Fleets"):

- ``outcome``: ``reached`` when every robot reached, else the worst robot's (highest exit
  code); ``collisions``, ``path_length_m``, ``charge_mAh``, ``energy_J``: sums over the
  robots (a robot-robot contact counts for both robots); ``duration_s``, ``sim_time_s``:
  the longest robot's;
- ``min_separation_m``: the closest approach of a robot's footprint to another robot's
  (footprint to footprint, from the pose samples of one instant) or a person;
- ``discomfort_s``: the time a person spent within :data:`DISCOMFORT_M` of a robot's
  footprint (0 without people).
"""

from __future__ import annotations

import math
from bisect import bisect_right
from dataclasses import replace

import numpy as np

from common.robot import BODY_LENGTH_M, BODY_WIDTH_M
from common.units import NS_PER_S as NS
from papf.launch.outcome import RunMonitor, RunResult

DISCOMFORT_M = 0.2    # [m] CrowdNav's discomfort distance


def footprint(x: float, y: float, yaw: float) -> np.ndarray:
    """The ROSbot's footprint corners (4 x 2) [m] at pose (x, y, yaw)."""
    hx, hy = BODY_LENGTH_M / 2, BODY_WIDTH_M / 2
    c, s = math.cos(yaw), math.sin(yaw)
    local = np.array([(hx, hy), (-hx, hy), (-hx, -hy), (hx, -hy)])
    return local @ np.array([[c, s], [-s, c]]) + (x, y)


def _point_segment(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    ab = b - a
    t = min(1.0, max(0.0, float(np.dot(p - a, ab) / np.dot(ab, ab))))
    return float(np.hypot(*(a + t * ab - p)))


def _inside(p: np.ndarray, poly: np.ndarray) -> bool:
    """``p`` in the convex, counter-clockwise polygon ``poly``."""
    edges = np.roll(poly, -1, axis=0) - poly
    rel = p - poly
    return bool(np.all(edges[:, 0] * rel[:, 1] - edges[:, 1] * rel[:, 0] >= 0))


def box_gap(a: np.ndarray, b: np.ndarray) -> float:
    """Distance between two convex footprints [m]; 0 when they touch or overlap."""
    if any(_inside(p, b) for p in a) or any(_inside(p, a) for p in b):
        return 0.0
    return min(_point_segment(p, poly[i], poly[(i + 1) % len(poly)])
               for pts, poly in ((a, b), (b, a)) for p in pts for i in range(len(poly)))


class SeparationMeter:
    """Closest approach between robots' footprints, from pose samples of equal stamps.

    Every complete instant is kept per robot as (stamp, running minimum), so the figure at
    a robot's ``t_end`` is exact whatever order samples and outcomes arrive in."""

    def __init__(self, names: list[str]):
        self.names = names
        self._at: dict[int, dict[str, tuple[float, float, float]]] = {}
        self._runs: dict[str, list[tuple[int, float]]] = {n: [] for n in names}

    def on_pose(self, name: str, stamp_ns: int, x: float, y: float, yaw: float) -> None:
        """A robot's pose sample; once every robot's of that stamp came, measure."""
        at = self._at.setdefault(stamp_ns, {})
        at[name] = (x, y, yaw)
        if len(at) < len(self.names):
            return
        del self._at[stamp_ns]
        for old in [t for t in self._at if t < stamp_ns]:   # never completed: a robot is gone
            del self._at[old]
        boxes = {n: footprint(*at[n]) for n in self.names}
        near = {n: math.inf for n in self.names}
        for i, a in enumerate(self.names):
            for b in self.names[i + 1:]:
                gap = box_gap(boxes[a], boxes[b])
                near[a], near[b] = min(near[a], gap), min(near[b], gap)
        for n, gap in near.items():
            runs = self._runs[n]
            runs.append((stamp_ns, min(gap, runs[-1][1]) if runs else gap))

    def min_m(self, name: str, t_end_ns: int) -> float:
        """Robot ``name``'s closest approach to another robot up to ``t_end_ns`` [m] (inf: none)."""
        i = bisect_right(self._runs[name], (t_end_ns, math.inf))
        return self._runs[name][i - 1][1] if i else math.inf


def robot_json(name: str, planner: str, r: RunResult, min_sep: float, discomfort_s: float) -> dict:
    """One robot's object in ``papf run --json``'s ``robots``."""
    d = r.to_json()
    out = {"name": name, "planner": planner}
    for k in ("outcome", "duration_s", "path_length_m", "charge_mAh", "energy_J", "collisions"):
        out[k] = d[k]
    out["min_separation_m"] = round(min_sep, 6) if math.isfinite(min_sep) else None
    out["discomfort_s"] = round(discomfort_s, 6)
    if r.reason:
        out["reason"] = r.reason
    return out


def fleet_result(robots: list[tuple[str, str, RunMonitor]], sep: SeparationMeter,
                 world: str, seed: int, wall_time_s: float,
                 discomfort_s: dict[str, float] | None = None) -> RunResult:
    """The fleet's :class:`RunResult` (module doc) with its ``robots`` objects; its planner
    is the robots' one, or their names joined by ``+``."""
    discomfort_s = discomfort_s or {}
    results = [(name, p, m.result(p, world, seed, wall_time_s)) for name, p, m in robots]
    worst = max(results, key=lambda nr: nr[2].exit_code)[2]
    outcome = "reached" if all(r.outcome == "reached" for _, _, r in results) else worst.outcome
    used = sorted({p for _, p, _ in results})
    total = RunResult(
        outcome=outcome, planner=used[0] if len(used) == 1 else "+".join(used), world=world, seed=seed,
        duration_s=max(r.duration_s for _, _, r in results),
        path_length_m=sum(r.path_length_m for _, _, r in results),
        charge_mAh=sum(r.charge_mAh for _, _, r in results),
        energy_J=sum(r.energy_J for _, _, r in results),
        collisions=sum(r.collisions for _, _, r in results),
        sim_time_s=max(r.sim_time_s for _, _, r in results), wall_time_s=wall_time_s,
        reason="; ".join(f"{n}: {r.outcome}" + (f" ({r.reason})" if r.reason else "")
                         for n, _, r in results if r.outcome != "reached"),
        faults=tuple(f for _, _, r in results for f in r.faults))
    seps = {n: sep.min_m(n, round(r.sim_time_s * NS)) for n, _, r in results}
    return replace(total, fleet=tuple(
        robot_json(n, p, r, seps[n], discomfort_s.get(n, 0.0)) for n, p, r in results),
        min_separation_m=min(seps.values()) if math.isfinite(min(seps.values())) else None,
        discomfort_s=sum(discomfort_s.values()))


def progress_figures(monitors: dict[str, RunMonitor],
                     goals: dict[str, tuple[float, float]]) -> tuple[float, float, float, str]:
    """(sim time [s], the farthest running robot's distance to its goal [m], the fleet's
    charge [mAh], "k/n done") for the progress line."""
    t = min((m.clock_ns for m in monitors.values()), default=0) / NS
    running = [m.distance_to(*goals[n]) for n, m in monitors.items() if not m.done]
    charge = sum(m.batteries[-1].charge_used_mAh for m in monitors.values() if m.batteries)
    done = sum(m.done for m in monitors.values())
    return t, max(running, default=0.0), charge, f"{done}/{len(monitors)} done"
