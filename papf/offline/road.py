"""Car-scale road worlds (``[robot] vehicle = "car"``, the IAPF paper's cases) offline.

The host follows the paper's vehicle model (eqs. 21-22, step ``step_s`` = 0.02 s) driven by
IAPF (``iapf``) or by the paper's traditional APF baseline (``apf``: eq. 12 obstacle field,
constant speed, no prediction, same road and cruise fields); the other vehicles follow
their world tracks and are seen as ground-truth tracks. The goal's x is a finish line.

:func:`plan_car` returns the one offline :class:`papf.offline.result.PlanResult` (through
:func:`papf.offline.run.simulate`), the full :class:`papf.offline.car.RoadRun` of
:func:`run_car` as its ``trace`` for the experiments' figures.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

from common.errors import ConfigError
from nodes.planner.iapf.algorithm import HostState, IAPFCore, IAPFParams
from nodes.planner.registry import car_variants, load_params
from nodes.planner.road import Lanes, Track
from papf.offline.car import RoadRun, run_road
from papf.offline.result import PlanResult
from worlds import Obstacle, World

#: car-scale run name -> label (the planners' declared ``car_variants``)
CAR_PLANNERS = {variant: v[1] for variant, v in car_variants().items()}


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
    strategy, _, changes, _ = car_variants()[planner]
    _, p = load_params(strategy, params_file, list(params))
    return dataclasses.replace(p, **changes)


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
             max_time_s: float = 60.0, whole_time: bool = False) -> PlanResult:
    """A car-scale world to the finish line, a collision or ``max_time_s`` [s]; with
    ``whole_time`` for all of ``max_time_s``, through contacts (the paper's figures)."""
    run = run_car(world, planner, params, params_file,
                  duration_s=max_time_s if whole_time else None, max_time_s=max_time_s)
    t_end = float(run.times[-1])
    reason = {"reached": f"passed x = {world.goal[0]:g} m",
              "collision": "the host's footprint touched a vehicle",
              "timeout": (f"ran the whole {max_time_s:g} s" if whole_time
                          else f"no outcome within {max_time_s:g} s")}[run.outcome]
    return PlanResult(world=world.name, planner=planner, seed=0, outcome=run.outcome,
                      reason=reason, path=run.states[:, :2].copy(), times=run.times,
                      headings=run.states[:, 3].copy(), duration_s=t_end, sim_time_s=t_end,
                      min_clearance_m=run.min_clearance_m, collisions=run.collisions,
                      motion="car", cycles=len(run.step_us),
                      road={k: v for k, v in run.summary().items()
                            if k not in ("collisions", "min_clearance_m")}, trace=run)
