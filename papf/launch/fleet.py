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
- ``discomfort_s``: the time a person spent within 0.2 m of a robot's footprint (0
  without people); both by :mod:`common.crowd_measures`, summed over robots at the top;
- per robot with people, the social measures of :mod:`common.crowd_measures` (Hall's
  zones: ``intimate_s`` ... ``social_n``; ``group_intrusions``, ``group_s``, ``min_ttc_s``).

A world with ``[[people]]`` and one robot runs this way too (one robot, its namespace the
run's), so its JSON has the people's figures and a ``robots`` list of one.
"""

from __future__ import annotations

import math
from bisect import bisect_right
from dataclasses import replace

import numpy as np

from common.crowd_measures import CrowdMeter
from common.units import NS_PER_S as NS
from papf.launch.outcome import RunMonitor, RunResult
from schemas import Odometry, People

PROGRESS_ROBOTS = 4       # [-] robots named one by one on the progress line
SAMPLE_NS = 100_000_000   # [ns] the measures' sampling period: the lockstep scan period


class FleetMeter:
    """Each robot's crowd measures (:class:`common.crowd_measures.CrowdMeter`: separation to
    the other robots' footprints and the people's discs, discomfort time), fed the instants
    for which every robot's pose sample (and the people's positions, if any) came.

    Every instant's figures are kept per robot as (stamp, min separation, discomfort), so
    the figures at a robot's ``t_end`` are exact whatever order samples and outcomes arrive in
    (each robot's samples arrive in stamp order, so instants complete in order). Instants
    are sampled every ``period_ns`` (default the 10 Hz control period: CrowdNav measures at
    its control step, 0.25 s; every 20 ms instant of 8 robots cost the launcher 22 % of a
    core, measured)."""

    def __init__(self, names: list[str], goals: dict[str, tuple[float, float]], people: bool,
                 period_ns: int = SAMPLE_NS, groups: tuple[tuple[int, ...], ...] = ()):
        self.names, self.people, self.period_ns = names, people, period_ns
        self.meter = CrowdMeter(goals, groups)
        self._at: dict[int, dict] = {}
        self._runs: dict[str, list[tuple[int, float, float]]] = {n: [] for n in names}
        self._measures: dict[str, list] = {n: [] for n in names}   # beside _runs, per instant

    def on_pose(self, name: str, msg: Odometry) -> None:
        """A robot's pose sample (``sim/pose``)."""
        if msg.stamp_ns % self.period_ns:
            return
        self._at.setdefault(msg.stamp_ns, {})[name] = (msg.x, msg.y, msg.yaw)
        self._check(msg.stamp_ns)

    def on_people(self, msg: People) -> None:
        """The people's positions of one instant (``sim/people``)."""
        if msg.stamp_ns % self.period_ns:
            return
        self._at.setdefault(msg.stamp_ns, {})[None] = msg
        self._check(msg.stamp_ns)

    def _check(self, t: int) -> None:
        at = self._at[t]
        if len(at) < len(self.names) + self.people:
            return
        del self._at[t]
        for old in [s for s in self._at if s < t]:   # never completed: a robot is gone
            del self._at[old]
        crowd = at.pop(None, None)
        xy = np.column_stack([crowd.x, crowd.y]) if crowd else np.zeros((0, 2))
        self.meter.update(t / NS, at, xy, np.asarray(crowd.radius if crowd else ()))
        for n, m in self.meter.results().items():
            self._runs[n].append((t, m.min_separation_m, m.discomfort_s))
            self._measures[n].append(m)

    def at(self, name: str, t_end_ns: int) -> tuple[float, float]:
        """Robot ``name``'s (min separation [m], inf: nobody to measure against; discomfort
        time [s]) up to ``t_end_ns``."""
        i = bisect_right(self._runs[name], (t_end_ns, math.inf, math.inf))
        return self._runs[name][i - 1][1:] if i else (math.inf, 0.0)

    def social_at(self, name: str, t_end_ns: int) -> dict:
        """Robot ``name``'s social measures up to ``t_end_ns`` as JSON figures ({} without
        people)."""
        i = bisect_right(self._runs[name], (t_end_ns, math.inf, math.inf))
        if not (i and self.people):
            return {}
        m = self._measures[name][i - 1]
        out = {k: round(getattr(m, k), 6) for k in SOCIAL}
        out["min_ttc_s"] = round(m.min_ttc_s, 6) if math.isfinite(m.min_ttc_s) else None
        return out


#: the social measures of common.crowd_measures.CrowdMeasures in a robot's JSON object
SOCIAL = ("intimate_s", "intimate_n", "personal_s", "personal_n", "social_s", "social_n",
          "group_intrusions", "group_s")


def robot_json(name: str, planner: str, r: RunResult, min_sep: float, discomfort_s: float,
               social: dict | None = None) -> dict:
    """One robot's object in ``papf run --json``'s ``robots`` (``social``: its social
    measures, :meth:`FleetMeter.social_at`)."""
    d = r.to_json()
    out = {"name": name, "planner": planner}
    for k in ("outcome", "duration_s", "path_length_m", "charge_mAh", "energy_J", "collisions"):
        out[k] = d[k]
    out["min_separation_m"] = round(min_sep, 6) if math.isfinite(min_sep) else None
    out["discomfort_s"] = round(discomfort_s, 6)
    out.update(social or {})
    if r.reason:
        out["reason"] = r.reason
    return out


def fleet_result(robots: list[tuple[str, str, RunMonitor]], meter: FleetMeter,
                 world: str, seed: int, wall_time_s: float) -> RunResult:
    """The fleet's :class:`RunResult` (module doc) with its ``robots`` objects; its planner
    is the robots' one, or their names joined by ``+``."""
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
    crowd = {n: meter.at(n, round(r.sim_time_s * NS)) for n, _, r in results}
    closest = min(sep for sep, _ in crowd.values())
    return replace(total, fleet=tuple(
        robot_json(n, p, r, *crowd[n], meter.social_at(n, round(r.sim_time_s * NS)))
        for n, p, r in results),
        min_separation_m=closest if math.isfinite(closest) else None,
        discomfort_s=sum(d for _, d in crowd.values()))


def progress_figures(monitors: dict[str, RunMonitor],
                     goals: dict[str, tuple[float, float]]) -> tuple[float, float, float, str]:
    """(sim time [s], the farthest running robot's distance to its goal [m], the fleet's
    charge [mAh], every robot's state: its distance to go, or its outcome) for the progress
    line (at most :data:`PROGRESS_ROBOTS` robots named, then how many are done)."""
    t = min((m.clock_ns for m in monitors.values()), default=0) / NS
    running = [m.distance_to(*goals[n]) for n, m in monitors.items() if not m.done]
    charge = sum(m.batteries[-1].charge_used_mAh for m in monitors.values() if m.batteries)
    done = sum(m.done for m in monitors.values())
    if len(monitors) > PROGRESS_ROBOTS:
        return t, max(running, default=0.0), charge, f"{done}/{len(monitors)} done"
    each = [f"{n} {m.outcome}" if m.done else f"{n} {m.distance_to(*goals[n]):.1f} m"
            for n, m in monitors.items()]
    return t, max(running, default=0.0), charge, " | ".join(each)
