"""The one offline closed loop of a planner on a 2-D world: ``papf plan``, the random-world
and paper-test experiments (offline) and the planner tests all drive through
:func:`closed_loop`.

Per control period ``dt``: a scan at the pose -> ``planner.step`` -> the command, through the
driver's :class:`~common.drive.CommandGate` if one is given (else applied as is),
drives an ideal unicycle (:func:`~common.drive.unicycle`, exact arcs every
:data:`SUBSTEP_S`, the driver's odometry period), with a clearance check at every substep.
What senses and what collides is passed in: the stack's LiDAR (pybullet) and the robot's
footprint box (:class:`FootprintChecker`) for ``papf plan``; exact numpy rays and a point
(:mod:`worlds.geometry`) for the planner tests (:mod:`tests.support.toysim`, worlds from :mod:`worlds.toy`). The start pose of a
seed is the world simulator's (:func:`start_pose`). No wheel slip or skid dynamics: that is what
the stack's pybullet driver adds.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from common.drive import CommandGate, unicycle
from common.quiet import import_quietly
from common.robot import MOVING_SPEED
from common.units import NS_PER_S as NS
from nodes.world_sim.physics import SimParams, jittered_start
from papf.offline.result import PlanResult
from schemas.messages import Odometry, Scan
from worlds import World
from worlds.bullet import MovingBodies, build_world
from worlds.messages import goal_message

p = import_quietly("pybullet")   # no build banner on stderr (common/quiet.py)

SUBSTEP_S = 0.02          # [s] integration and collision-check step (driver odometry period)
CLEARANCE_CAP_M = 1.0     # [m] clearances above this are not resolved (reported as the cap)
TERMINAL = ("reached", "stagnated", "failed")


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
        self.moving = MovingBodies(self.cid, world, self.bodies)
        shape = p.createCollisionShape(p.GEOM_BOX, halfExtents=[sx / 2, sy / 2, sz / 2],
                                       physicsClientId=self.cid)
        self.robot = p.createMultiBody(baseMass=0.0, baseCollisionShapeIndex=shape,
                                       basePosition=[0.0, 0.0, self.z], physicsClientId=self.cid)

    def clearance(self, x: float, y: float, yaw: float, t_ns: int = 0) -> float:
        """Signed distance footprint-obstacles [m] (< 0: overlap), capped at CLEARANCE_CAP_M,
        with moving obstacles where they are at sim time ``t_ns``."""
        if self.moving:
            self.moving.place(t_ns)
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
    """The world's start plus the stack driver's seeded hand-placement jitter (the same draws
    as :class:`nodes.world_sim.physics.SimBase` for the same seed)."""
    return jittered_start(world.start, np.random.default_rng(seed))


def closed_loop(world: World, planner, name: str, seed: int, start: tuple[float, float, float],
                scan: Callable[[float, float, float, int], Scan],
                clearance: Callable[[float, float, float, int], float], max_time_s: float,
                dt: float = 0.1, gate: CommandGate | None = None, keep_states: bool = False,
                stop_on_collision: bool = True) -> PlanResult:
    """Drive ``planner`` from ``start`` to an outcome (see the module doc); ``scan(x, y, yaw,
    t_ns)`` senses, ``clearance(x, y, yaw, t_ns)`` [m] < 0 is a collision."""
    drive = Drive(world, planner, name, seed, start, scan, clearance, max_time_s, dt, gate,
                  keep_states, stop_on_collision)
    while not drive.outcome:
        drive.cycle()
    return drive.result()


class Drive:
    """:func:`closed_loop` one control period at a time (:meth:`cycle`), for loops that
    interleave several robots (papf/offline/crowd.py); arguments as :func:`closed_loop`."""

    def __init__(self, world: World, planner, name: str, seed: int,
                 start: tuple[float, float, float], scan, clearance, max_time_s: float,
                 dt: float = 0.1, gate: CommandGate | None = None, keep_states: bool = False,
                 stop_on_collision: bool = True):
        self.world, self.planner, self.name, self.seed = world, planner, name, seed
        self.scan, self.clearance, self.gate = scan, clearance, gate
        self.max_time_s, self.dt = max_time_s, dt
        self.keep_states, self.stop_on_collision = keep_states, stop_on_collision
        self.x, self.y, self.yaw = start
        self.step_ns = int(round(dt * NS))
        self.n_sub = max(1, int(round(dt / SUBSTEP_S)))
        self.v = self.w = 0.0
        planner.set_goal(goal_message(world))
        self.rows, self.states = [(0.0, *start)], []
        self.outcome, self.reason, self.t_end, self.moved_ns = "", "", 0, None
        self.min_clear = clearance(*start, 0)
        self.collisions, self.t, self.cycles = 0, 0, 0

    def cycle(self) -> None:
        """One control period: scan, plan, drive the substeps, check clearance."""
        x, y, yaw, t, gate = self.x, self.y, self.yaw, self.t, self.gate
        step_ns, n_sub = self.step_ns, self.n_sub
        sub_s = self.dt / n_sub
        cmd, state, status = self.planner.step(
            self.scan(x, y, yaw, t), Odometry(stamp_ns=t, x=x, y=y, yaw=yaw, v=self.v, w=self.w))
        self.cycles += 1
        if self.keep_states:
            self.states.append(state)
        if status.state in TERMINAL:
            self.outcome, self.reason, self.t_end = status.state, status.reason, t
            return
        if gate is not None:
            gate.command(cmd.v, cmd.w, t)
        for k in range(n_sub):
            t_sub = t + (k * step_ns) // n_sub
            v, w = gate.output(t_sub, sub_s)[:2] if gate is not None else (cmd.v, cmd.w)
            self.v, self.w = v, w
            x, y, yaw = unicycle(x, y, yaw, v, w, sub_s)
            if self.moved_ns is None and abs(v) > MOVING_SPEED:
                self.moved_ns = t_sub
            c = self.clearance(x, y, yaw, t + ((k + 1) * step_ns) // n_sub)
            self.min_clear = min(self.min_clear, c)
            if c < 0.0:
                self.collisions += 1
                if self.stop_on_collision:
                    self.t_end = t + ((k + 1) * step_ns) // n_sub
                    self.outcome = "collision"
                    self.reason = f"footprint overlaps an obstacle at ({x:.2f}, {y:.2f})"
                    break
        self.x, self.y, self.yaw = x, y, yaw
        self.t = t = t + step_ns
        self.rows.append((self.t_end / NS if self.outcome else t / NS, x, y, yaw))
        if not self.outcome and t >= self.max_time_s * NS:
            self.outcome, self.reason, self.t_end = ("timeout",
                                                     f"no outcome within {self.max_time_s:g} s", t)

    def result(self) -> PlanResult:
        """The run so far as a :class:`PlanResult`."""
        arr = np.array(self.rows)
        start_ns = self.moved_ns if self.moved_ns is not None else self.t_end
        return PlanResult(world=self.world.name, planner=self.name, seed=self.seed,
                          outcome=self.outcome, reason=self.reason, path=arr[:, 1:3],
                          times=arr[:, 0], headings=arr[:, 3],
                          duration_s=max(0, self.t_end - start_ns) / NS,
                          sim_time_s=self.t_end / NS, min_clearance_m=float(self.min_clear),
                          collisions=self.collisions, motion="unicycle", cycles=self.cycles,
                          states=self.states)
