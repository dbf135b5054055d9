"""The one offline entry point: :func:`simulate` runs a planner of the registry on a world
without the process stack and returns one :class:`~papf.offline.result.PlanResult`.

It picks the motion model from the world and ``motion`` (used by ``papf plan`` and every
experiment's offline runs):

- ``motion="robot"`` (default), 2-D world: the ROSbot — LiDAR sim, the driver's command gate,
  a unicycle and its footprint (:mod:`papf.offline.plan`, :mod:`papf.offline.unicycle`);
- ``motion="robot"``, 3-D world (spheres): a point robot (:mod:`papf.offline.point3d`);
- ``motion="robot"``, car-scale road world (``vehicle = "car"``): the IAPF paper's vehicle
  model (:mod:`papf.offline.road`, :mod:`papf.offline.car`);
- ``motion="robot"``, a world with ``[[robots]]`` or ``[[people]]``: every robot as above, in
  lockstep with the people (:mod:`papf.offline.crowd`);
- ``motion="fixed-step"``: Wang's MATLAB point, planners ``wang-apf`` and ``wang``
  (:mod:`papf.offline.wang_step`).
"""

from __future__ import annotations

import math
from pathlib import Path

from common.errors import ConfigError
from papf.offline.plan import DEFAULT_MAX_TIME_S, param_sets, plan_robot
from papf.offline.result import PlanResult
from worlds import World, load_world

MOTIONS = ("robot", "fixed-step")


def simulate(world: World | str | Path, planner: str, params=None, seed: int = 0,
             max_time_s: float = DEFAULT_MAX_TIME_S, dt: float = 0.1, lidar=None,
             keep_states: bool = False, params_file: str | Path | None = None,
             motion: str = "robot", whole_time: bool = False,
             passing: str | None = None) -> PlanResult:
    """Run ``planner`` on ``world`` (a World, packaged name or path) to an outcome.

    ``params``: planner settings (``{"name": value}`` or ``["name=value"]``, as ``--set``);
    ``seed``: LiDAR noise and start jitter; ``max_time_s`` [s]: sim-time limit; ``dt`` [s]:
    control period; ``lidar``: scan geometry and noise (2-D; default the stack's);
    ``keep_states``: the planner's state per cycle in ``states``; ``whole_time``: car-scale
    worlds only, drive all of ``max_time_s`` through contacts (the IAPF paper's figures);
    ``passing``: a fleet's passing layer, ``off`` | ``orca`` (None: ``orca`` for two or more
    robots, :func:`papf.offline.crowd.passing_for`).
    """
    if motion not in MOTIONS:
        raise ConfigError(f"motion {motion!r}; valid: {list(MOTIONS)}")
    if not isinstance(world, World):
        world = load_world(world)
    if not (dt > 0 and math.isfinite(dt)):
        raise ConfigError(f"dt = {dt!r} s must be a finite number > 0")
    if not max_time_s > 0:
        raise ConfigError(f"max_time_s = {max_time_s!r} must be > 0")
    sets = param_sets(params)
    if whole_time and (motion != "robot" or world.vehicle != "car"):
        raise ConfigError("whole_time: car-scale road worlds only ([robot] vehicle = \"car\")")
    if motion == "fixed-step":
        return _fixed_step(world, planner, sets, params_file)
    if world.robots or world.has_people:
        from papf.offline.crowd import plan_crowd

        return plan_crowd(world, planner, sets, params_file, seed, max_time_s, dt, keep_states,
                          lidar, passing)
    if world.vehicle == "car":
        from papf.offline.road import plan_car

        return plan_car(world, planner, sets, params_file, max_time_s, whole_time)
    return plan_robot(world, planner, sets, params_file, seed, max_time_s, dt, lidar, keep_states)


def _fixed_step(world: World, planner: str, sets: list[str], params_file) -> PlanResult:
    """Wang's published walk: Table 1's settings as the paper has them, nothing else."""
    from papf.offline.wang_step import PLANNER_METHODS, fixed_step

    if planner not in PLANNER_METHODS:
        raise ConfigError(f"motion fixed-step: planner {planner!r}; valid: {sorted(PLANNER_METHODS)}")
    if sets or params_file is not None:
        raise ConfigError("motion fixed-step runs Wang's Table 1 as published: planner settings "
                          "(--set, --params, --preset) do not apply")
    return fixed_step(world, PLANNER_METHODS[planner])
