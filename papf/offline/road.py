"""Car-scale road worlds (``[robot] vehicle = "car"``, the IAPF paper's cases) offline.

The host follows the paper's vehicle model (eqs. 21-22, step ``step_s`` = 0.02 s) driven by
IAPF (``iapf``) or by the paper's traditional APF baseline (``apf``: eq. 12 obstacle field,
constant speed, no prediction, same road and cruise fields); the other vehicles follow
their world tracks and are seen as ground-truth tracks. The goal's x is a finish line.

:func:`plan_car` returns a :class:`papf.offline.plan.PlanResult` (as ``papf plan`` prints it) and
:func:`run_car` the full :class:`papf.offline.car.RoadRun` for experiments and figures.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

from common.errors import ConfigError
from nodes.planner.iapf import HostState, IAPFCore, IAPFParams
from nodes.planner.iapf_fields import Lanes, Track
from nodes.planner.registry import load_params
from papf.offline.car import RoadRun, run_road
from papf.offline.result import PlanResult
from worlds import Obstacle, World

CAR_PLANNERS = {"iapf": "IAPF", "iapf-np": "IAPF without prediction", "apf": "traditional APF"}


def lanes_of(world: World) -> Lanes:
    """The world's ``[road]`` as the planner's :class:`Lanes`."""
    if world.road is None:
        raise ConfigError(f"world {world.name!r} has no [road]")
    return Lanes(world.road.y_min, world.road.lane_width, world.road.lanes)


def footprint(ob: Obstacle) -> tuple[float, float]:
    """(length along the heading, width) [m] of a 2-D obstacle."""
    length, width = ob.model.footprint(ob)
    return float(length), float(width)


def mover(ob: Obstacle, ident: int):
    """Sim time [s] -> the obstacle's ground-truth :class:`Track`."""
    length, width = footprint(ob)

    def at(t: float) -> Track:
        s = ob.state_at(t)
        return Track(s.x, s.y, s.yaw, s.vx, s.vy, length, width, ident)
    return at


def car_params(planner: str, params=(), params_file: str | Path | None = None) -> IAPFParams:
    """IAPF settings (registry defaults, preset, file, ``--set``) for a car-scale planner name."""
    if planner not in CAR_PLANNERS:
        raise ConfigError(f"planner {planner!r} does not run on car-scale road worlds; "
                          f"valid: {sorted(CAR_PLANNERS)}")
    _, p = load_params("iapf", params_file, list(params))
    if planner == "iapf-np":
        p = dataclasses.replace(p, prediction=False)
    if planner == "apf":
        p = dataclasses.replace(p, traditional=True, prediction=False)
    return p


def run_car(world: World, planner: str, params=(), params_file=None,
            duration_s: float | None = None, max_time_s: float = 60.0) -> RoadRun:
    """One run: for ``duration_s`` (the whole time, through collisions) or, without it, to the
    finish line / first collision / ``max_time_s``."""
    if world.vehicle != "car":
        raise ConfigError(f"world {world.name!r} is not a car-scale world ([robot] vehicle = \"car\")")
    p = car_params(planner, params, params_file)
    lanes = lanes_of(world)
    start = HostState(world.start[0], world.start[1], p.v_cruise, world.start[2])
    movers = [mover(ob, i) for i, ob in enumerate(world.obstacles)]
    y_goal = lanes.centre(lanes.lane_of(world.goal[1]))
    if duration_s is not None:
        return run_road(IAPFCore(p), start, movers, lanes, duration_s, planner, y_goal)
    return run_road(IAPFCore(p), start, movers, lanes, max_time_s, planner, y_goal,
                    finish_x=world.goal[0], stop_on_collision=True)


def plan_car(world: World, planner: str, params=(), params_file=None,
             max_time_s: float = 60.0) -> PlanResult:
    """``papf plan`` on a car-scale world: to the finish line, a collision or the time limit."""
    run = run_car(world, planner, params, params_file, max_time_s=max_time_s)
    t_end = float(run.times[-1])
    reason = {"reached": f"passed x = {world.goal[0]:g} m",
              "collision": "the host's footprint touched a vehicle",
              "timeout": f"no outcome within {max_time_s:g} s"}[run.outcome]
    return PlanResult(world=world.name, planner=planner, seed=0, outcome=run.outcome,
                      reason=reason, path=run.states[:, :2].copy(), times=run.times,
                      headings=run.states[:, 3].copy(), duration_s=t_end, sim_time_s=t_end,
                      min_clearance_m=run.min_clearance_m, collisions=run.collisions,
                      road={k: v for k, v in run.summary().items()
                            if k not in ("collisions", "min_clearance_m")})
