"""Offline planning: run a planner of the registry on a world without the process stack.

``plan(world, "papf")`` -> :class:`PlanResult` (path, outcome, duration, length).

2-D worlds — the real :class:`nodes.planner.core.Planner` in closed loop with:

- scans from :class:`nodes.lidar_sim.core.LidarSim` (pybullet rays, seeded noise), one per
  control period ``dt`` (10 Hz, as the stack); the start pose jittered as the stack's sim
  driver does for the same seed (:func:`start_pose`);
- the ROSbot command safety of the driver (:class:`nodes.base_driver.limits.CommandGate`:
  |v| <= 0.9 m/s, |w| <= 3 rad/s, 1 m/s^2, 4 rad/s^2) feeding an ideal unicycle integrated
  exactly every :data:`SUBSTEP_S` (the driver's odometry period). No wheel slip or skid
  dynamics: that is what the stack's pybullet driver adds;
- a collision check of the robot's footprint box (the driver's chassis,
  ``SimParams.chassis_size``, 0.200 x 0.235 m) against the world's obstacles in pybullet, the
  same geometry the stack's driver collides with (:mod:`worlds.bullet`).

3-D worlds (Wang, Sec. 5: sphere obstacles): :mod:`papf.plan3d`, a point robot.

Outcomes as ``papf run``: reached | stagnated | collision | timeout | failed.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import pybullet as p

from common.errors import ConfigError
from common.units import NS_PER_S as NS
from nodes.base_driver.limits import CommandGate, RosbotLimits
from nodes.base_driver.sim import SimParams
from nodes.lidar_sim.core import LidarParams, LidarSim
from nodes.planner.registry import make_planner
from papf.monitor import MOVING_SPEED
from papf.plan3d import plan_3d
from papf.plan_result import PlanResult, write_path  # noqa: F401 - part of this module's API
from schemas.messages import Odometry
from worlds import World, load_world
from worlds.bullet import build_world
from worlds.messages import goal_message

SUBSTEP_S = 0.02          # [s] integration and collision-check step (driver odometry period)
CLEARANCE_CAP_M = 1.0     # [m] clearances above this are not resolved (reported as the cap)
DEFAULT_MAX_TIME_S = 300.0  # [s] sim-time limit, as `papf run --timeout`
TERMINAL = ("reached", "stagnated", "failed")


def param_sets(params: Mapping[str, object] | Sequence[str] | None) -> list[str]:
    """``{"v_max": 0.3}`` or ``["v_max=0.3"]`` -> the registry's ``--set`` strings."""
    if params is None:
        return []
    if isinstance(params, Mapping):
        return [f"{k}={v}" for k, v in params.items()]
    return [str(s) for s in params]


def plan(world: World | str | Path, planner_name: str, params=None, seed: int = 0,
         max_time_s: float = DEFAULT_MAX_TIME_S, dt: float = 0.1,
         lidar: LidarParams | None = None, keep_states: bool = False,
         params_file: str | Path | None = None) -> PlanResult:
    """Run ``planner_name`` on ``world`` (a World, packaged name or path) to an outcome.

    ``params``: planner settings (``{"name": value}`` or ``["name=value"]``, as ``--set``);
    ``seed``: LiDAR noise and start jitter; ``dt`` [s]: control period; ``lidar``: scan geometry and noise
    (default: the stack's). In 3-D worlds ``lidar`` is ignored (see :mod:`papf.plan3d`).
    """
    if not isinstance(world, World):
        world = load_world(world)
    if not (dt > 0 and math.isfinite(dt)):
        raise ConfigError(f"dt = {dt!r} s must be a finite number > 0")
    if not max_time_s > 0:
        raise ConfigError(f"max_time_s = {max_time_s!r} must be > 0")
    planner = make_planner(planner_name, params_file, param_sets(params))
    if world.dims == 3:
        return plan_3d(world, planner, planner_name, seed, max_time_s, dt, keep_states)
    return _plan_2d(world, planner, planner_name, seed, max_time_s, dt, lidar, keep_states)


class FootprintChecker:
    """The robot's footprint box against the world's obstacles (pybullet closest points)."""

    def __init__(self, world: World, chassis: tuple[float, float, float] | None = None,
                 clearance_above_floor: float | None = None):
        sim = SimParams()
        sx, sy, sz = chassis or sim.chassis_size
        z0 = sim.chassis_clearance if clearance_above_floor is None else clearance_above_floor
        self.z = z0 + sz / 2
        self.cid = p.connect(p.DIRECT)
        self.bodies = build_world(self.cid, world)
        shape = p.createCollisionShape(p.GEOM_BOX, halfExtents=[sx / 2, sy / 2, sz / 2],
                                       physicsClientId=self.cid)
        self.robot = p.createMultiBody(baseMass=0.0, baseCollisionShapeIndex=shape,
                                       basePosition=[0.0, 0.0, self.z], physicsClientId=self.cid)

    def clearance(self, x: float, y: float, yaw: float) -> float:
        """Signed distance footprint-obstacles [m] (< 0: overlap), capped at CLEARANCE_CAP_M."""
        quat = p.getQuaternionFromEuler([0.0, 0.0, yaw])
        p.resetBasePositionAndOrientation(self.robot, [x, y, self.z], quat, physicsClientId=self.cid)
        lo, hi = p.getAABB(self.robot, physicsClientId=self.cid)
        cap = CLEARANCE_CAP_M
        near = p.getOverlappingObjects([lo[0] - cap, lo[1] - cap, lo[2] - cap],
                                       [hi[0] + cap, hi[1] + cap, hi[2] + cap],
                                       physicsClientId=self.cid) or []
        best = cap
        for body, _link in near:
            if body == self.robot:
                continue
            for pt in p.getClosestPoints(self.robot, body, cap, physicsClientId=self.cid):
                best = min(best, pt[8])
        return best

    def close(self) -> None:
        if self.cid is not None and p.isConnected(self.cid):
            p.disconnect(self.cid)
        self.cid = None


def start_pose(world: World, seed: int) -> tuple[float, float, float]:
    """The world's start plus the stack driver's seeded hand-placement jitter (same draws as
    :class:`nodes.base_driver.sim.SimBase` for the same seed)."""
    prm = SimParams()
    rng = np.random.default_rng(seed)
    jitter = rng.normal(0.0, 1.0, 3) * (prm.start_xy_sd, prm.start_xy_sd, prm.start_yaw_sd)
    return tuple(float(c) for c in np.add(world.start, jitter))


def _unicycle(x: float, y: float, yaw: float, v: float, w: float, dt: float):
    """Exact integration of a unicycle with constant (v, w) over dt."""
    if abs(w) < 1e-9:
        return x + v * dt * math.cos(yaw), y + v * dt * math.sin(yaw), yaw
    yaw2 = yaw + w * dt
    return (x + v / w * (math.sin(yaw2) - math.sin(yaw)),
            y - v / w * (math.cos(yaw2) - math.cos(yaw)), yaw2)


def _plan_2d(world, planner, name, seed, max_time_s, dt, lidar, keep_states) -> PlanResult:
    step_ns = int(round(dt * NS))
    n_sub = max(1, int(round(dt / SUBSTEP_S)))
    sub_s = dt / n_sub
    x, y, yaw = start_pose(world, seed)
    v = w = 0.0
    gate = CommandGate(RosbotLimits())
    planner.set_goal(goal_message(world))
    rows, states = [(0.0, x, y, yaw)], []
    outcome, reason, t_end, moved_ns = "", "", 0, None
    with LidarSim(world, lidar, seed) as sensor:
        checker = FootprintChecker(world)
        try:
            min_clear = checker.clearance(x, y, yaw)
            t = 0
            while not outcome:
                scan = sensor.scan(x, y, yaw, t)
                cmd, state, status = planner.step(scan, Odometry(stamp_ns=t, x=x, y=y, yaw=yaw,
                                                                 v=v, w=w))
                if keep_states:
                    states.append(state)
                if status.state in TERMINAL:
                    outcome, reason, t_end = status.state, status.reason, t
                    break
                gate.command(cmd.v, cmd.w, t)
                for k in range(n_sub):
                    t_sub = t + (k * step_ns) // n_sub
                    v, w, _ = gate.output(t_sub, sub_s)
                    x, y, yaw = _unicycle(x, y, yaw, v, w, sub_s)
                    if moved_ns is None and abs(v) > MOVING_SPEED:
                        moved_ns = t_sub
                    c = checker.clearance(x, y, yaw)
                    min_clear = min(min_clear, c)
                    if c < 0.0:
                        t_end = t + ((k + 1) * step_ns) // n_sub
                        outcome = "collision"
                        reason = f"footprint overlaps an obstacle at ({x:.2f}, {y:.2f})"
                        break
                t += step_ns
                rows.append((t_end / NS if outcome else t / NS, x, y, yaw))
                if not outcome and t >= max_time_s * NS:
                    outcome, reason, t_end = "timeout", f"no outcome within {max_time_s:g} s", t
        finally:
            checker.close()
    arr = np.array(rows)
    start_ns = moved_ns if moved_ns is not None else t_end
    return PlanResult(world=world.name, planner=name, seed=seed, outcome=outcome, reason=reason,
                      path=arr[:, 1:3], times=arr[:, 0], headings=arr[:, 3],
                      duration_s=max(0, t_end - start_ns) / NS, sim_time_s=t_end / NS,
                      min_clearance_m=float(min_clear), collisions=int(outcome == "collision"),
                      states=states)
