"""The LiDAR's simulated source, an RPLIDAR A3 on the ROSbot: pybullet ray casting, no
transport (pure core); the real one is ``ros2_source.py``.

A 360 deg planar scan (docs/architecture.md "The robot"): ``beams`` rays (300 by default, the L of the
PAPF paper's Table 1) at ``angle_min + i * angle_increment`` with ``angle_min = -pi``,
``angle_increment = 2 pi / beams``, counter-clockwise in the sensor frame, like the
``sensor_msgs/LaserScan`` that ``rplidar_ros`` publishes. Ranges 0.2-25 m
(RPLIDAR A3 datasheet). Rays are cast with ``rayTestBatch`` in the sensor's own
pybullet DIRECT client that holds only the world's obstacles (no robot, so no
self-hits; moving obstacles placed at the scan's sim time), at :data:`SENSOR_HEIGHT` above the floor (below the default 0.5 m
obstacle height).

In a fleet, :meth:`LidarSim.place_bodies` puts the other robots (boxes of the ROSbot's
200 x 235 x 220 mm body) and the people (discs in the scan plane) at their poses of the scan's instant
(``Bodies``, from the world simulator) before the rays are cast; a person is a sphere centred on
the scan plane, whose section there is the person's disc (cheaper to cast against).

Invalid readings: no return within ``range_max`` -> ``inf``; a return closer than
``range_min`` -> ``inf`` too, because the A3 reports distance 0 ("no valid
measurement") there and ``rplidar_ros`` publishes a 0 reading as ``inf``.

Noise: Gaussian, sigma = ``noise_sd + noise_rel * range`` [m]. The A3 datasheet gives
"accuracy 1 % of range (<= 3 m)"; the default is a constant 1 cm (1 % at 1 m, the
distance the planners react at), ``noise_rel`` follows the datasheet's form when set.
The noise of a scan is drawn from ``numpy.random.default_rng([seed, stamp_ns])`` (a
fleet's robot k > 0: ``[seed, stamp_ns, k]``, so robots' noises differ), so the scan of a
given instant is identical whatever the process timing.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from operator import itemgetter

import numpy as np

from common import robot
from common.errors import ConfigError
from common.params import check_value
from common.quiet import import_quietly
from nodes.lidar_sim.options import OPTIONS
from schemas.messages import Bodies, Scan
from worlds import World
from worlds.bullet import MovingBodies, build_world

p = import_quietly("pybullet")   # no build banner on stderr (common/quiet.py)

RANGE_MIN = 0.2          # [m] RPLIDAR A3 datasheet
RANGE_MAX = 25.0         # [m] RPLIDAR A3 datasheet (white objects)
SENSOR_HEIGHT = robot.LIDAR_HEIGHT_M   # [m] scan plane above the floor (common.robot)
SENSOR_X = robot.LIDAR_X_M   # [m] sensor ahead of the robot centre (common.robot)


_BODY, _FRACTION = itemgetter(0), itemgetter(2)   # of a rayTestBatch hit


@dataclass(frozen=True)
class LidarParams:
    """Scan geometry and noise (units in comments)."""

    beams: int = 300                   # [-] rays per 360 deg revolution
    range_min: float = RANGE_MIN       # [m]
    range_max: float = RANGE_MAX       # [m]
    noise_sd: float = 0.01             # [m] constant part of the range noise sigma
    noise_rel: float = 0.0             # [-] part of sigma proportional to the range
    sensor_x: float = SENSOR_X         # [m] sensor position in the robot frame
    sensor_y: float = 0.0              # [m]
    sensor_yaw: float = 0.0            # [rad] sensor x axis relative to the robot's
    height: float = SENSOR_HEIGHT      # [m] scan plane above the floor

    def __post_init__(self) -> None:
        for name in ("beams", "noise_sd", "noise_rel"):
            check_value(name, getattr(self, name), OPTIONS[name])
        if not 0 < self.range_min < self.range_max or not math.isfinite(self.range_max):
            raise ConfigError(f"lidar ranges {self.range_min!r}..{self.range_max!r} m must satisfy "
                              "0 < range_min < range_max < inf")
        if not self.height > 0:
            raise ConfigError(f"lidar height = {self.height!r} m must be > 0")

    @property
    def angle_min(self) -> float:
        return -math.pi

    @property
    def angle_increment(self) -> float:
        return 2 * math.pi / self.beams


class LidarSim:
    """Cast a scan at a robot pose in ``world`` (see module doc)."""

    def __init__(self, world: World, params: LidarParams | None = None, seed: int = 0,
                 robot: int = 0):
        self.params = prm = params or LidarParams()
        if seed < 0:
            raise ConfigError(f"lidar seed = {seed} must be >= 0")
        self.seed = seed
        self.robot = robot    # index in the world's [[robots]]: each robot's noise its own
        angles = prm.angle_min + prm.angle_increment * np.arange(prm.beams) + prm.sensor_yaw
        self._angles = angles               # beam directions in the robot frame [rad]
        self.cid = p.connect(p.DIRECT)
        try:
            self.bodies = build_world(self.cid, world)
            self.moving = MovingBodies(self.cid, world, self.bodies)
            self._robots: list[int] = []          # other robots' bodies (place_bodies)
            self._people: list = []               # (body, radius) of each person, or None
        except Exception:
            p.disconnect(self.cid)
            raise

    def place_bodies(self, bodies: Bodies) -> None:
        """Put the other robots (boxes of the ROSbot's body) and the people where ``bodies``
        says; bodies beyond what it lists wait far below the floor. A person is a sphere of
        its radius centred on the scan plane: in that plane, the same disc as a cylinder's,
        and a ray meets a sphere far more cheaply (measured: 50 people as cylinders made a
        scan 6.5x slower, as spheres 1.7x)."""
        cid = self.cid
        shapes = ((self._robots, len(bodies.robots), self._robot_body),
                  (self._people, len(bodies.person_x), None))
        for pool, n, make in shapes:
            while len(pool) < n:
                pool.append(make() if make else None)
        for k, body in enumerate(self._robots):
            if k < len(bodies.robots):
                quat = p.getQuaternionFromEuler([0, 0, bodies.robot_yaw[k]])
                pos = [bodies.robot_x[k], bodies.robot_y[k], robot.BODY_HEIGHT_M / 2]
            else:
                pos, quat = [0.0, 0.0, -100.0], [0, 0, 0, 1]
            p.resetBasePositionAndOrientation(body, pos, quat, physicsClientId=cid)
        for k in range(len(self._people)):
            if k < len(bodies.person_x) and bodies.person_radius[k] > 0:
                r = bodies.person_radius[k]
                if self._people[k] is None or self._people[k][1] != r:
                    if self._people[k] is not None:
                        p.removeBody(self._people[k][0], physicsClientId=cid)
                    self._people[k] = (self._person_body(r), r)
                pos = [bodies.person_x[k], bodies.person_y[k], self.params.height]
            elif self._people[k] is None:
                continue
            else:
                pos = [0.0, 0.0, -100.0]
            p.resetBasePositionAndOrientation(self._people[k][0], pos, [0, 0, 0, 1],
                                              physicsClientId=cid)

    def _robot_body(self) -> int:
        half = [robot.BODY_LENGTH_M / 2, robot.BODY_WIDTH_M / 2, robot.BODY_HEIGHT_M / 2]
        shape = p.createCollisionShape(p.GEOM_BOX, halfExtents=half, physicsClientId=self.cid)
        return p.createMultiBody(0, shape, basePosition=[0, 0, -100], physicsClientId=self.cid)

    def _person_body(self, radius: float) -> int:
        shape = p.createCollisionShape(p.GEOM_SPHERE, radius=radius, physicsClientId=self.cid)
        return p.createMultiBody(0, shape, basePosition=[0, 0, -100], physicsClientId=self.cid)

    def true_ranges(self, pose_x: float, pose_y: float, pose_yaw: float) -> np.ndarray:
        """Noise-free distance to the first obstacle per beam [m]; ``inf`` if none within range_max."""
        prm = self.params
        c, s = math.cos(pose_yaw), math.sin(pose_yaw)
        ox = pose_x + c * prm.sensor_x - s * prm.sensor_y
        oy = pose_y + s * prm.sensor_x + c * prm.sensor_y
        directions = self._angles + pose_yaw
        n = prm.beams
        start = np.empty((n, 3))
        start[:, 0] = ox
        start[:, 1] = oy
        start[:, 2] = prm.height
        end = start.copy()
        end[:, 0] += prm.range_max * np.cos(directions)
        end[:, 1] += prm.range_max * np.sin(directions)
        # float64 arrays straight to pybullet (the same numbers as lists, without building them)
        hits = p.rayTestBatch(start, end, numThreads=1, physicsClientId=self.cid)
        # hit = (body id or -1, link, fraction of the ray, position, normal); C-level maps,
        # not a Python loop per beam
        fraction = np.fromiter(map(_FRACTION, hits), float, n)
        fraction[np.fromiter(map(_BODY, hits), np.int64, n) < 0] = np.inf
        return fraction * prm.range_max

    def scan(self, pose_x: float, pose_y: float, pose_yaw: float, stamp_ns: int) -> Scan:
        """The noisy scan taken at robot pose (x [m], y [m], yaw [rad]) at sim time ``stamp_ns``.

        Moving obstacles are placed where they are at ``stamp_ns`` first.
        """
        prm = self.params
        if self.moving:
            self.moving.place(stamp_ns)
        ranges = self.true_ranges(pose_x, pose_y, pose_yaw)
        hit = np.isfinite(ranges)
        if prm.noise_sd > 0 or prm.noise_rel > 0:
            key = [self.seed, stamp_ns % 2**64] + ([self.robot] if self.robot else [])
            rng = np.random.default_rng(key)
            noise = rng.normal(0.0, 1.0, prm.beams)
            ranges[hit] += (prm.noise_sd + prm.noise_rel * ranges[hit]) * noise[hit]
        ranges[(ranges < prm.range_min) | (ranges > prm.range_max)] = np.inf
        return Scan(stamp_ns=stamp_ns, angle_min=prm.angle_min, angle_increment=prm.angle_increment,
                    range_min=prm.range_min, range_max=prm.range_max,
                    ranges=ranges.astype(np.float32), sensor_x=prm.sensor_x, sensor_y=prm.sensor_y,
                    sensor_yaw=prm.sensor_yaw)

    def close(self) -> None:
        if self.cid is not None and p.isConnected(self.cid):
            p.disconnect(self.cid)
        self.cid = None

    def __enter__(self) -> LidarSim:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
