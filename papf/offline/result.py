"""The one result of every offline run (:func:`papf.offline.run.simulate`, any motion model)
and its path file."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from common.errors import ConfigError
from common.outfiles import output


@dataclass
class PlanResult:
    """One offline run. ``path`` rows are positions (x, y) or (x, y, z) [m] per control cycle
    (per iteration for Wang's fixed step, which has no time: ``times`` counts iterations)."""

    world: str
    planner: str
    seed: int
    outcome: str                   # reached | stagnated | collision | timeout | failed
    reason: str
    path: np.ndarray               # (N, D) [m]
    times: np.ndarray              # (N,) sim time of each row [s]
    headings: np.ndarray           # (N,) yaw [rad] (2-D); empty in 3-D
    duration_s: float              # first motion -> outcome [s] (as RunResult.duration_s)
    sim_time_s: float              # sim time of the outcome [s]
    min_clearance_m: float         # closest approach of the footprint / point to an obstacle [m]
    collisions: int
    motion: str = "unicycle"       # the motion model: unicycle | point3d | fixed-step | car | crowd
    cycles: int = 0                # planner cycles (force evaluations) made
    states: list = field(default_factory=list)   # keep_states: PlannerState (2-D) or Plan (3-D) per cycle
    road: dict = field(default_factory=dict)     # road worlds: left_road, lane_changes, min/max speed
    units_per_m: float = 1.0       # fixed step: the paper's map units per metre (Wang's gains are in them)
    trace: object = None           # car: the whole RoadRun (speeds, temporary goals, step times, vehicles); crowd: the CrowdRun
    crowd: dict = field(default_factory=dict)    # crowd worlds: people, and one object per robot

    @property
    def length_m(self) -> float:
        """Path length [m]."""
        if self.path.shape[0] < 2:
            return 0.0
        return float(np.sum(np.linalg.norm(np.diff(self.path, axis=0), axis=1)))

    def summary(self) -> dict:
        """The `papf plan --json` object (no path)."""
        return {"outcome": self.outcome, "planner": self.planner, "world": self.world,
                "seed": self.seed, "motion": self.motion, "cycles": self.cycles, "duration_s": round(self.duration_s, 6),
                "path_length_m": round(self.length_m, 6), "sim_time_s": round(self.sim_time_s, 6),
                "collisions": self.collisions,
                "min_clearance_m": round(self.min_clearance_m, 6), **self.road, **self.crowd,
                "reason": self.reason}


def write_path(result: PlanResult, out: str | Path, force: bool = False, inputs=()) -> None:
    """The path as CSV (``t,x,y[,z],yaw``) or JSON (summary + ``path``), by file suffix
    (:func:`common.outfiles.output`: an existing ``out`` only with ``force``, never an input)."""
    out = Path(out)
    with output(out, inputs, force) as tmp:
        tmp.write_text(path_text(result, out.suffix.lower()))


def path_text(result: PlanResult, suffix: str) -> str:
    """The text of :func:`write_path` for ``suffix`` (``.csv`` or ``.json``)."""
    dims = result.path.shape[1]
    cols = ["t", "x", "y", "z"][: dims + 1]
    if suffix == ".json":
        doc = {**result.summary(), "columns": cols,
               "path": [[float(t), *map(float, row)] for t, row in zip(result.times, result.path, strict=True)]}
        return json.dumps(doc)
    if suffix != ".csv":
        raise ConfigError(f"path file suffix {suffix!r}: must be .csv or .json")
    lines = [",".join(cols + (["yaw"] if result.headings.size else []))]
    for i, (t, row) in enumerate(zip(result.times, result.path, strict=True)):
        vals = [f"{t:.3f}", *(f"{v:.5f}" for v in row)]
        if result.headings.size:
            vals.append(f"{result.headings[i]:.5f}")
        lines.append(",".join(vals))
    return "\n".join(lines) + "\n"
