"""The world simulator's physics: simulated ROSbot 2.0 PRO bases in pybullet (rigid bodies,
the world's obstacles, people's bodies), no transport (pure core).

The robot (docs/architecture.md "The robot"; geometry and masses from husarion/rosbot_ros
``rosbot_description``): a chassis box of 0.200 x 0.235 x 0.100 m (the footprint,
so it covers the wheels; obstacle contacts are found on it) and four wheels of
r = 0.0425 m, 0.036 m wide, 0.074 kg each, at x = +-wheelbase/2 = +-0.053 m,
y = +-track/2 = +-0.096 m; 2.84 kg in total. Each wheel is a revolute joint
under pybullet ``VELOCITY_CONTROL`` with a motor torque limit
(:data:`MOTOR_TORQUE_LIMIT`), so speed changes are physically bounded (by that torque
and by tyre friction, mu g ~ 10 m/s^2; the command gate's 1 m/s^2 is tighter). Poses
are in the world file's frame: the robot starts at ``world.start`` plus jitter.

Wheel-ground friction. Bullet's multibody solver takes its two friction directions
from fixed world axes, which makes a skid-steer robot turn differently at yaw 0 and
yaw 45 deg (measured: in-place rotation stalls near yaw 0 and pi/2). So the
wheels have zero Bullet friction with the floor and each wheel gets a Coulomb tyre
force, direction-invariant, computed here every step and applied at its contact
point: ``F = -mu N s / sqrt(|s|^2 + eps^2)`` with ``s`` the contact slip velocity
(floor-relative velocity of the contact point minus the rim speed ``omega r``) and
``N = m g / 4`` (flat floor, no load transfer: an assumption). ``eps`` smooths the
Coulomb law's jump at zero slip so a robot at rest does not chatter (0.05 m/s, an
assumption; trajectories barely change for 0.005-0.1 m/s).

Skid steering. For in-place rotation the Coulomb forces balance when the wheels'
contact speed is ``w (a^2 + b^2) / b`` (a = wheelbase/2, b = track/2), i.e. the
wheel targets use an effective track ``track * (1 + (wheelbase/track)^2)`` =
0.192 * 1.305 = 0.251 m. The real ROSbot's controller uses 0.186 * 1.36 = 0.253 m
(``wheel_separation`` x ``wheel_separation_multiplier``, "checked on our office
floor"), which this model reproduces.

Noise (one ``numpy.random.Generator(seed)``, drawn once at construction): start-pose
jitter (hand placement), per-wheel friction coefficient and per-wheel rolling radius
(calibration error that makes straight driving curve slightly). Same seed -> the
same trajectory bit for bit; another seed -> another one.

Odometry is ground truth from pybullet; the real ROSbot publishes EKF-filtered
wheel+IMU odometry (``/odometry/filtered``), which is smoother but drifts.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from common import robot
from common.errors import ConfigError
from common.quiet import import_quietly
from schemas.messages import WHEEL_NAMES, Odometry, WheelStates
from worlds import World
from worlds.bullet import MERGED, MovingBodies, add_ground, build_world
from worlds.index import StaticIndex

p = import_quietly("pybullet")   # no build banner on stderr (common/quiet.py)
# the calls made every physics step, looked up once
_base_pose, _base_velocity = p.getBasePositionAndOrientation, p.getBaseVelocity
_joint_states, _external_force, _WORLD_FRAME = p.getJointStates, p.applyExternalForce, p.WORLD_FRAME
_contact_points = p.getContactPoints

GRAVITY = 9.81                 # [m/s^2]
STEP_NS = 4_000_000            # [ns] physics step, 250 Hz (docs/architecture.md "Time")
SETTLE_STEPS = 25              # steps (0.1 s) at rest before t = 0 so the robot sits on the floor
MOTOR_TORQUE_LIMIT = 1.5       # [N*m] per wheel: rosbot_description wheel joint effort limit and the
                               # Gazebo plugin's max_wheel_torque (assumption: the real gear motor
                               # delivers about this much)
TOP_SPEED = robot.TOP_SPEED_M_S   # [m/s]
PERSON_HEIGHT_M = 1.8          # [m] a person's cylinder (assumption; anything above the robot)


@dataclass(frozen=True)
class SimParams:
    """Physical and noise parameters of the simulated ROSbot (units in comments)."""

    mass: float = robot.MASS_KG           # [kg] total, with LiDAR and camera
    wheel_mass: float = robot.WHEEL_MASS_KG   # [kg] per wheel
    chassis_size: tuple[float, float, float] = (0.200, 0.235, 0.100)  # [m] x, y, z (footprint)
    chassis_clearance: float = 0.025      # [m] floor to chassis bottom (body collision box ~0.023)
    com_above_axle: float = 0.02          # [m] centre of mass above the wheel axles (rosbot_description)
    wheel_radius: float = robot.WHEEL_RADIUS_M   # [m]
    wheel_width: float = robot.WHEEL_WIDTH_M     # [m]
    track: float = robot.TRACK_M                 # [m] left-right wheel distance
    wheelbase: float = robot.WHEELBASE_M         # [m] front-rear wheel distance
    friction: float = 1.0                 # [-] tyre-floor Coulomb coefficient (Gazebo model: mu = 1)
    slip_eps: float = 0.05                # [m/s] Coulomb regularisation (see module doc)
    motor_torque_limit: float = MOTOR_TORQUE_LIMIT  # [N*m] per wheel
    wheel_speed_limit: float = TOP_SPEED / robot.WHEEL_RADIUS_M   # [rad/s] 29.4, top speed / r
    icr_factor: float | None = None       # [-] effective-track factor; None = 1 + (wheelbase/track)^2
    start_xy_sd: float = 0.01             # [m] start position jitter (hand placement)
    start_yaw_sd: float = math.radians(1.0)  # [rad] start heading jitter
    friction_sd: float = 0.05             # [-] relative per-wheel friction variation
    radius_sd: float = 0.003              # [-] relative per-wheel rolling-radius error
    step_ns: int = field(default=STEP_NS)  # [ns]

    def __post_init__(self) -> None:
        positive = ("mass", "wheel_mass", "wheel_radius", "wheel_width", "track", "wheelbase",
                    "friction", "slip_eps", "motor_torque_limit", "wheel_speed_limit")
        for name in positive:
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ConfigError(f"SimParams.{name} = {value!r} must be a finite number > 0")
        if self.mass <= 4 * self.wheel_mass:
            raise ConfigError(f"SimParams.mass = {self.mass} kg must exceed the four wheels' "
                              f"{4 * self.wheel_mass} kg")
        if not isinstance(self.step_ns, int) or self.step_ns <= 0:
            raise ConfigError(f"SimParams.step_ns = {self.step_ns!r} must be an integer > 0")

    @property
    def effective_track(self) -> float:
        """[m] track used to turn (v, w) into wheel speeds (skid-steer ICR model)."""
        chi = self.icr_factor if self.icr_factor is not None else 1 + (self.wheelbase / self.track) ** 2
        return self.track * chi


@dataclass(frozen=True)
class Contact:
    """A robot touching an obstacle (index in ``world.obstacles``) or another robot, at a point [m]."""

    obstacle: int                 # -1: another robot
    x: float
    y: float
    robot: int = -1               # index of the other robot touched (fleet order), else -1
    person: int = -1              # index of the person touched ([[people]] order), else -1


def jittered_start(start, rng: np.random.Generator, prm: SimParams | None = None,
                   ) -> tuple[float, float, float]:
    """``start`` (x, y, yaw) plus the hand-placement jitter: three normal draws from ``rng``
    scaled by ``start_xy_sd`` / ``start_yaw_sd``. The sim draws them first from
    ``default_rng(seed)``, so the offline tools get the same start for the same seed."""
    prm = prm or SimParams()
    jitter = rng.normal(0.0, 1.0, 3) * (prm.start_xy_sd, prm.start_xy_sd, prm.start_yaw_sd)
    return tuple(float(c) for c in np.add(start, jitter))  # type: ignore[return-value]


class SimBase:
    """Simulated ROSbots (one, or a fleet: ``starts``) in a pybullet DIRECT client holding
    ``world``'s obstacles; methods take the robot's index ``i`` (0: the first)."""

    def __init__(self, world: World, seed: int = 0, params: SimParams | None = None,
                 starts: list[tuple[float, float, float]] | None = None):
        if world.dims != 2:
            raise ConfigError(f"world {world.name!r} is {world.dims}-D; the ROSbot sim needs a 2-D world")
        self.params = prm = params or SimParams()
        self.world = world
        rng = np.random.default_rng(seed)
        # Each robot's draws in turn from the one rng: jitter, friction, radius. Robot 0's
        # are the first draws of the run's rng, as with one robot (same seed, same start).
        noise = []
        for nominal in starts or [tuple(world.start[:3])]:
            start = jittered_start(nominal, rng, prm)
            mu = prm.friction * np.clip(1 + prm.friction_sd * rng.normal(0.0, 1.0, 4), 0.5, 1.5)
            r_eff = prm.wheel_radius * (1 + prm.radius_sd * rng.normal(0.0, 1.0, 4))
            noise.append((start, [float(m) for m in mu], [float(r) for r in r_eff]))
        self._load = prm.mass * GRAVITY / 4                          # [N] per wheel
        a, b = prm.wheelbase / 2, prm.track / 2
        self._wx = (a, a, -a, -a)                                     # [m] WHEEL_NAMES order
        self._wy = (b, -b, b, -b)
        self._joints = [0, 1, 2, 3]
        # Per-wheel constants of the tyre model, computed once: (index, x, y, rolling radius,
        # -mu N). ``-mu * N / d`` is evaluated as ``(-mu * N) / d``, so the product can be
        # kept: the same operations in the same order, bit for bit (tests/test_driver_sim.py).
        self._mu_of = [mu for _, mu, _ in noise]                      # [-] per robot, per wheel
        self._r_eff_of = [r for _, _, r in noise]                     # [m] rolling radius
        self._tyres_of = [tuple((i, self._wx[i], self._wy[i], r[i], -mu[i] * self._load)
                                for i in range(4)) for _, mu, r in noise]
        self._mu, self._r_eff, self._tyres = self._mu_of[0], self._r_eff_of[0], self._tyres_of[0]
        self._eps2 = prm.slip_eps ** 2                                # [m^2/s^2]
        self._track_eff = prm.effective_track                         # [m]
        self.t_ns = 0
        self.cid = p.connect(p.DIRECT)
        try:
            self._setup(world, [start for start, _, _ in noise])
        except Exception:
            p.disconnect(self.cid)
            raise

    # -- construction -------------------------------------------------------
    def _setup(self, world: World, starts: list[tuple[float, float, float]]) -> None:
        cid, prm = self.cid, self.params
        p.setGravity(0, 0, -GRAVITY, physicsClientId=cid)
        p.setTimeStep(prm.step_ns * 1e-9, physicsClientId=cid)
        p.setPhysicsEngineParameter(deterministicOverlappingPairs=1, physicsClientId=cid)
        self.ground = add_ground(cid)
        self._obstacle_index: dict[int, int] = {}               # body id -> obstacle index
        self.obstacles = build_world(cid, world, self._obstacle_index)
        self._static_index: StaticIndex | None = None            # on the first mesh contact
        self.moving = MovingBodies(cid, world, self.obstacles)   # kinematic, on sim time
        self.robots = [self._build_robot(start) for start in starts]   # body ids, fleet order
        self._robot_index = {body: i for i, body in enumerate(self.robots)}
        self.people: list[int] = []                                   # add_people
        self._person_index: dict[int, int] = {}
        self._people_here: list[bool] = []                            # place_people
        self._targets_of = [(0.0, 0.0)] * len(self.robots)           # [rad/s] left, right
        self.robot = self.robots[0]
        for _ in range(SETTLE_STEPS):
            self._physics_step()

    def _build_robot(self, start: tuple[float, float, float]) -> int:
        cid, prm = self.cid, self.params
        r, zc = prm.wheel_radius, prm.com_above_axle
        sx, sy, sz = prm.chassis_size
        chassis = p.createCollisionShape(
            p.GEOM_BOX, halfExtents=[sx / 2, sy / 2, sz / 2],
            collisionFramePosition=[0, 0, prm.chassis_clearance + sz / 2 - r - zc], physicsClientId=cid)
        wheel = p.createCollisionShape(
            p.GEOM_CYLINDER, radius=r, height=prm.wheel_width,
            collisionFrameOrientation=p.getQuaternionFromEuler([math.pi / 2, 0, 0]), physicsClientId=cid)
        robot = p.createMultiBody(
            baseMass=prm.mass - 4 * prm.wheel_mass, baseCollisionShapeIndex=chassis,
            basePosition=[start[0], start[1], r + zc],
            baseOrientation=p.getQuaternionFromEuler([0, 0, start[2]]),
            linkMasses=[prm.wheel_mass] * 4, linkCollisionShapeIndices=[wheel] * 4,
            linkVisualShapeIndices=[-1] * 4,
            linkPositions=[[x, y, -zc] for x, y in zip(self._wx, self._wy, strict=True)],
            linkOrientations=[[0, 0, 0, 1]] * 4, linkInertialFramePositions=[[0, 0, 0]] * 4,
            linkInertialFrameOrientations=[[0, 0, 0, 1]] * 4, linkParentIndices=[0] * 4,
            linkJointTypes=[p.JOINT_REVOLUTE] * 4, linkJointAxis=[[0, 1, 0]] * 4,
            physicsClientId=cid)
        for j in self._joints:  # the tyre model below replaces Bullet's floor friction
            p.changeDynamics(robot, j, lateralFriction=0.0, physicsClientId=cid)
        p.setJointMotorControlArray(robot, self._joints, p.VELOCITY_CONTROL,
                                    targetVelocities=[0.0] * 4,
                                    forces=[prm.motor_torque_limit] * 4, physicsClientId=cid)
        self._targets = (0.0, 0.0)                                    # [rad/s] left, right
        return robot

    # -- control and stepping -------------------------------------------------
    def set_twist(self, v: float, w: float, i: int = 0) -> tuple[float, float]:
        """Command robot ``i``'s body velocities [m/s, rad/s]; returns its (left, right) wheel
        targets [rad/s]."""
        prm = self.params
        half = w * self._track_eff / 2
        lim = prm.wheel_speed_limit
        left = max(-lim, min(lim, (v - half) / prm.wheel_radius))
        right = max(-lim, min(lim, (v + half) / prm.wheel_radius))
        targets = self._targets_of[i]
        if left != targets[0] or right != targets[1]:  # motor settings persist
            p.setJointMotorControlArray(self.robots[i], self._joints, p.VELOCITY_CONTROL,
                                        targetVelocities=[left, right, left, right],
                                        forces=[prm.motor_torque_limit] * 4, physicsClientId=self.cid)
            self._targets_of[i] = (left, right)
        return left, right

    def step(self) -> None:
        """Advance the physics by one step (4 ms) with the current wheel targets.

        Moving obstacles are placed at the step's end time first, so after the step the
        whole scene (robot, obstacles, contacts) belongs to sim time ``t_ns``.
        """
        if self.moving:
            self.moving.place(self.t_ns + self.params.step_ns)
        self._physics_step()
        self.t_ns += self.params.step_ns

    def _physics_step(self) -> None:
        self._apply_tyre_forces()
        for i in range(1, len(self.robots)):   # the fleet's other robots, in order
            self._apply_tyre_forces(i)
        p.stepSimulation(physicsClientId=self.cid)

    def _apply_tyre_forces(self, n: int = 0) -> None:
        """The Coulomb tyre force of every wheel (module doc), applied at its contact point.

        Plain floats, not numpy: 4-element arrays cost more in overhead than they save. Three
        state reads and four force calls per step (pybullet has no batched form of either);
        the per-wheel constants are precomputed (``_tyres``) and the bound functions looked
        up once. Same operations, same order as the formula: bit for bit.
        """
        cid, robot = self.cid, self.robots[n]
        (px, py, _), (qx, qy, qz, qw) = _base_pose(robot, physicsClientId=cid)
        (vx, vy, _), (_, _, w) = _base_velocity(robot, physicsClientId=cid)
        yaw = math.atan2(2 * (qw * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz))   # _yaw(quat)
        c, s = math.cos(yaw), math.sin(yaw)
        vbx, vby = c * vx + s * vy, -s * vx + c * vy                  # body-frame velocity
        states = _joint_states(robot, self._joints, physicsClientId=cid)
        eps2, sqrt, force = self._eps2, math.sqrt, _external_force
        for i, wx, wy, r_eff, k_n in self._tyres_of[n]:
            slip_x = vbx - w * wy - states[i][1] * r_eff
            slip_y = vby + w * wx
            k = k_n / sqrt(slip_x * slip_x + slip_y * slip_y + eps2)
            fx, fy = k * slip_x, k * slip_y
            force(robot, i, (c * fx - s * fy, s * fx + c * fy, 0.0),
                  (px + c * wx - s * wy, py + s * wx + c * wy, 0.0), _WORLD_FRAME, physicsClientId=cid)

    # -- state ------------------------------------------------------------------
    def pose(self, i: int = 0) -> tuple[float, float, float]:
        """Ground-truth (x [m], y [m], yaw [rad]) of robot ``i``'s centre in the world frame."""
        (x, y, _), quat = p.getBasePositionAndOrientation(self.robots[i], physicsClientId=self.cid)
        return x, y, _yaw(quat)

    def odometry(self, stamp_ns: int, i: int = 0) -> Odometry:
        """Robot ``i``'s ground-truth pose and body-frame forward speed and yaw rate."""
        x, y, yaw = self.pose(i)
        (vx, vy, _), (_, _, w) = p.getBaseVelocity(self.robots[i], physicsClientId=self.cid)
        v = math.cos(yaw) * vx + math.sin(yaw) * vy
        return Odometry(stamp_ns=stamp_ns, x=x, y=y, yaw=yaw, v=v, w=w)

    def velocity(self, i: int = 0) -> tuple[float, float]:
        """Robot ``i``'s ground-truth velocity (vx, vy) [m/s] in the world frame."""
        (vx, vy, _), _ = p.getBaseVelocity(self.robots[i], physicsClientId=self.cid)
        return vx, vy

    def wheel_states(self, stamp_ns: int, i: int = 0) -> WheelStates:
        """Robot ``i``'s wheel speeds [rad/s] and motor torques of the last step [N*m]."""
        states = p.getJointStates(self.robots[i], self._joints, physicsClientId=self.cid)
        return WheelStates(stamp_ns=stamp_ns, speed=tuple(float(s[1]) for s in states),
                           torque=tuple(float(s[3]) for s in states), names=WHEEL_NAMES)

    def contacts(self, i: int = 0) -> list[Contact]:
        """Obstacles (and other robots) robot ``i`` touches after the last step, one entry each.

        Only the chassis is checked: its box covers the wheels' footprint, so an obstacle
        reaches it first (unless lower than the 2.5 cm ground clearance). Another robot is
        any part of its body; its entry has ``obstacle = -1`` and ``robot`` = its index.
        """
        points = _contact_points(bodyA=self.robots[i], linkIndexA=-1, physicsClientId=self.cid)
        if not points:   # the common case, every step of a run without contact
            return []
        seen: dict = {}   # obstacle index, or ("robot" | "person", index) -> Contact
        for cp in points:
            other, person = self._robot_index.get(cp[2]), self._person_index.get(cp[2])
            if other is not None or person is not None:
                key = ("robot", other) if other is not None else ("person", person)
                if key not in seen:
                    seen[key] = Contact(-1, float(cp[6][0]), float(cp[6][1]),
                                        -1 if other is None else other,
                                        -1 if person is None else person)
                continue
            index = self._obstacle_index.get(cp[2])
            if index == MERGED:   # a mesh of many static obstacles: the one at the contact
                index = self._nearest_static(cp[6][0], cp[6][1])
            if index is not None and index not in seen:
                seen[index] = Contact(index, float(cp[6][0]), float(cp[6][1]))
        return list(seen.values())

    def _nearest_static(self, x: float, y: float) -> int | None:
        """Index of the static obstacle nearest to (x, y) [m] (a contact with a merged mesh)."""
        if self._static_index is None:   # built on the first contact with a mesh
            self._static_index = StaticIndex(self.world)
        return self._static_index.nearest(x, y)

    def add_people(self, radii) -> None:
        """Bodies for people (cylinders of ``radii`` [m], :data:`PERSON_HEIGHT_M` tall, moved
        kinematically by :meth:`place_people`); a robot touching one is a contact."""
        for r in radii:
            shape = p.createCollisionShape(p.GEOM_CYLINDER, radius=float(r), height=PERSON_HEIGHT_M,
                                           physicsClientId=self.cid)
            body = p.createMultiBody(0, shape, basePosition=[0, 0, -100], physicsClientId=self.cid)
            self._person_index[body] = len(self.people)
            self.people.append(body)

    def place_people(self, xy, present=None) -> None:
        """Put each person's body at its (x, y) [m]; one not ``present`` (a replayed person
        outside their recording's rows) far below the floor, where nothing touches it."""
        present = [True] * len(self.people) if present is None else list(present)
        before = self._people_here or [True] * len(self.people)
        for k, (body, (x, y), here) in enumerate(zip(self.people, xy, present, strict=True)):
            if not (here or before[k]):
                continue                        # parked, and stays so
            pos = [float(x), float(y), PERSON_HEIGHT_M / 2] if here else [0.0, 0.0, -100.0]
            p.resetBasePositionAndOrientation(body, pos, [0, 0, 0, 1], physicsClientId=self.cid)
        self._people_here = present

    def close(self) -> None:
        if self.cid is not None and p.isConnected(self.cid):
            p.disconnect(self.cid)
        self.cid = None

    def __enter__(self) -> SimBase:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _yaw(quat) -> float:
    x, y, z, w = quat
    return math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


__all__ = ["Contact", "MOTOR_TORQUE_LIMIT", "STEP_NS", "SimBase", "SimParams", "WHEEL_NAMES"]
