"""``papf experiment crowd --compare-models``: ORCA (pyrvo) against the social-force model
(pysocialforce) on the same small scenes, and their cost per step.

Scenes (people of radius 0.3 m at 1 m/s, ``dt`` = 0.1 s, seed 0, 30 s at most):

- ``head-on-open``: two people walk at each other along y = 0 in the open;
- ``head-on-corridor``: the same between walls at y = +-1 m (a 2 m corridor);
- ``robot-in-the-way``: one person walks down that corridor at a robot standing on its line
  (its disc: the footprint's circumscribed radius, 0.154 m), 5 cm off the person's axis;
- ``hall-20``: the 20 people of ``papf experiment crowd``'s scene (seed 0), all of one model,
  around a robot standing at the start, 300 steps: the wall time of a step [ms] (median of 3).

Per scene and model: the smallest gap between bodies [m] (< 0: they overlap; the social-force
model has no body radius), the largest step aside [m], whether everyone arrived, when [s].
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np

from common.crowd import Crowd
from common.robot import FOOTPRINT_RADIUS_M
from worlds import World
from worlds.fleet import PersonSpec
from worlds.kinds.wall import segment_wall

MODELS = ("orca", "social_force")
DT_S = 0.1
STEPS = 300
CORRIDOR = (segment_wall(-2, 1.0, 12, 1.0), segment_wall(-2, -1.0, 12, -1.0))


def _world(obstacles=()) -> World:
    return World("compare", "", (0.0, 0.0, 0.0), (1.0, 0.0), 0.1, obstacles=tuple(obstacles))


def _behaviour(model: str, scene: str) -> dict:
    """One scene's figures for one model (module doc)."""
    two = [PersonSpec((0.0, 0.0), ((10.0, 0.0),), model=model),
           PersonSpec((10.0, 0.0), ((0.0, 0.0),), model=model)]
    robots = []
    if scene == "head-on-open":
        crowd = Crowd(two, _world(), 0)
    elif scene == "head-on-corridor":
        crowd = Crowd(two, _world(CORRIDOR), 0)
    else:
        crowd = Crowd(two[:1], _world(CORRIDOR), 0)
        robots = [(5.0, 0.05, 0.0, 0.0)]
    gap, aside, t_arrive = math.inf, 0.0, math.nan
    for k in range(STEPS):
        crowd.step(DT_S, robots)
        p = crowd.positions
        if robots:
            d = math.hypot(p[0, 0] - 5.0, p[0, 1] - 0.05) - 0.3 - FOOTPRINT_RADIUS_M
        else:
            d = math.hypot(*(p[0] - p[1])) - 0.6
        gap, aside = min(gap, d), max(aside, float(np.abs(p[:, 1]).max()))
        if crowd.arrived().all():
            t_arrive = round((k + 1) * DT_S, 1)
            break
    return {"scene": scene, "model": model, "min_gap_m": round(gap, 3),
            "max_aside_m": round(aside, 3), "arrived": bool(crowd.arrived().all()),
            "arrival_s": t_arrive, "step_ms": ""}


def _cost(model: str) -> dict:
    """The wall time of one step of 20 people of ``model`` in the crowd hall [ms]."""
    from papf.experiments.crowd import crowd_scene

    world, _ = crowd_scene(20, 0)
    people = [dataclasses.replace(p, model=model) for p in world.people]
    times = []
    for _ in range(3):
        crowd = Crowd(people, world, 0)
        crowd.step(DT_S, [(0.0, 0.0, 0.0, 0.0)])      # the first: building, numba's compile
        t0 = time.perf_counter()
        for _ in range(STEPS):
            crowd.step(DT_S, [(0.0, 0.0, 0.0, 0.0)])
        times.append((time.perf_counter() - t0) / STEPS * 1e3)
    return {"scene": "hall-20", "model": model, "min_gap_m": "", "max_aside_m": "",
            "arrived": "", "arrival_s": "", "step_ms": round(float(np.median(times)), 3)}


def compare_models() -> list[dict]:
    """Every scene with every model, then the cost rows (module doc)."""
    rows = [_behaviour(m, s) for s in ("head-on-open", "head-on-corridor", "robot-in-the-way")
            for m in MODELS]
    return rows + [_cost(m) for m in MODELS]
