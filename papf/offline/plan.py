"""The ROSbot offline on a 2-D world: :func:`plan_robot` (called by
:func:`papf.offline.run.simulate`, the one offline entry point).

The real :class:`nodes.planner.core.Planner` in the one offline closed loop
(:func:`papf.offline.unicycle.closed_loop`) with the stack's robot: scans from
:class:`nodes.lidar_sim.core.LidarSim` (pybullet rays, seeded noise) every control period
``dt`` (10 Hz, as the stack), the start pose jittered as the world simulator does for the same
seed, the driver's :class:`~common.drive.CommandGate` (|v| <= 0.9 m/s,
|w| <= 3 rad/s, 1 m/s^2, 4 rad/s^2) and the footprint box of the driver's chassis
(0.200 x 0.235 m) against the world's obstacles in pybullet (:mod:`worlds.bullet`); in 3-D
worlds (spheres) the point robot of :mod:`papf.offline.point3d`.

Outcomes as ``papf run``: reached | stagnated | collision | timeout | failed.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from common.drive import CommandGate, RosbotLimits
from nodes.lidar_sim.core import LidarParams, LidarSim
from nodes.planner.registry import make_planner
from nodes.planner.road import Lanes
from nodes.world_sim.physics import SimParams
from papf.offline.car import road_figures
from papf.offline.point3d import plan_3d
from papf.offline.result import PlanResult
from papf.offline.unicycle import FootprintChecker, closed_loop, start_pose
from worlds import World

DEFAULT_MAX_TIME_S = 300.0  # [s] sim-time limit, as `papf run --timeout`


def param_sets(params: Mapping[str, object] | Sequence[str] | None) -> list[str]:
    """``{"v_max": 0.3}`` or ``["v_max=0.3"]`` -> the registry's ``--set`` strings."""
    if params is None:
        return []
    if isinstance(params, Mapping):
        return [f"{k}={v}" for k, v in params.items()]
    return [str(s) for s in params]


def plan_robot(world: World, planner_name: str, sets: list[str], params_file, seed: int,
               max_time_s: float, dt: float, lidar: LidarParams | None,
               keep_states: bool) -> PlanResult:
    """The registry's ``planner_name`` with ``--set`` strings ``sets`` on the ROSbot (2-D) or
    the point robot (3-D), to an outcome within ``max_time_s`` [s] of sim time."""
    planner = make_planner(planner_name, params_file, sets)
    if world.dims == 3:
        return plan_3d(world, planner, planner_name, seed, max_time_s, dt, keep_states)
    return _plan_2d(world, planner, planner_name, seed, max_time_s, dt, lidar, keep_states)


def _plan_2d(world, planner, name, seed, max_time_s, dt, lidar, keep_states) -> PlanResult:
    """The stack's robot offline: the LiDAR sim, the driver's command gate, the footprint."""
    with LidarSim(world, lidar, seed) as sensor:
        checker = FootprintChecker(world)
        try:
            result = closed_loop(world, planner, name, seed, start_pose(world, seed),
                                 sensor.scan, checker.clearance, max_time_s, dt,
                                 CommandGate(RosbotLimits()), keep_states)
        finally:
            checker.close()
    if world.road is not None:
        lanes = Lanes(world.road.y_min, world.road.lane_width, world.road.lanes)
        size = SimParams().chassis_size
        result.road = road_figures(lanes, result.times, result.path, result.headings,
                                   (size[0], size[1]))
    return result
