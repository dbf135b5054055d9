"""The world simulator's pure core: the sim time grid, the robots' command gates, physics,
people, collisions and the bodies each LiDAR sees.

No zenoh here. :class:`WorldCore` advances a :class:`~nodes.world_sim.physics.SimBase`
one publication instant at a time (docs/architecture.md "Time" and "Lockstep"):

- ``outputs()`` -> the messages of instant ``t``, in the protocol's order:
  ``sim/pose``, ``odom``, ``wheels``, ``clock``, then any ``events`` that happened
  since the previous instant (collision, watchdog_stop);
- ``command(twist)`` -> feeds the robot's :class:`~common.drive.CommandGate`
  (the command counts as issued at ``min(stamp, t)``) and says whether it is *the*
  answer to the scan of instant ``t`` (``stamp_ns == t``);
- ``advance()`` -> physics steps of 4 ms up to the next instant, the gate's
  rate-limited output applied at every step.

Collisions are debounced: one ``collision`` event per contact episode per obstacle;
an episode ends after :data:`COLLISION_GAP_NS` without contact.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from common.drive import DRIVER_OPTIONS, ODOM_HZ, CommandGate, RosbotLimits
from common.errors import ConfigError
from common.params import check_value
from common.units import NS_PER_S, period_ns
from nodes.world_sim.physics import SimBase, SimParams
from schemas.messages import Bodies, Clock, Event, People, Twist
from worlds import World

# Event.source of this node's events: on the bus the simulator stands where the robot's base
# driver stands (its liveliness token is base_driver too), so readers see a sim run and a robot
# run alike
SOURCE = "base_driver"
COLLISION_GAP_NS = 200_000_000    # [ns] contact-free time that ends a contact episode (assumption)


@dataclass(frozen=True)
class WorldConfig:
    """Time grid, the robots' command limits and the physics of the world simulator."""

    odom_period_ns: int = 20_000_000     # [ns] sim/pose, odom, wheels, clock (50 Hz)
    scan_period_ns: int = 100_000_000    # [ns] lockstep instants (10 Hz, the RPLIDAR A3 rate)
    limits: RosbotLimits = field(default_factory=RosbotLimits)
    sim: SimParams = field(default_factory=SimParams)

    def __post_init__(self) -> None:
        step = self.sim.step_ns
        if self.odom_period_ns <= 0 or self.odom_period_ns % step:
            raise ConfigError(f"odometry period {self.odom_period_ns} ns must be a positive "
                              f"multiple of the {step} ns physics step (--odom-hz: e.g. 250, 50, "
                              "10)")
        if self.scan_period_ns <= 0 or self.scan_period_ns % self.odom_period_ns:
            raise ConfigError(f"scan period {self.scan_period_ns} ns must be a positive multiple "
                              f"of the odometry period {self.odom_period_ns} ns (--odom-hz: a "
                              "multiple of the scan rate, e.g. 250, 50, 10)")

    @classmethod
    def from_rates(cls, odom_hz: float = ODOM_HZ, scan_hz: float = 10.0, watchdog_s: float = 0.5,
                   sim: SimParams | None = None) -> WorldConfig:
        for name, value in (("odom_hz", odom_hz), ("scan_hz", scan_hz), ("watchdog", watchdog_s)):
            check_value(name, value, DRIVER_OPTIONS[name])
        return cls(odom_period_ns=period_ns(odom_hz, "odometry rate"),
                   scan_period_ns=period_ns(scan_hz, "scan rate"),
                   limits=RosbotLimits(watchdog_ns=round(watchdog_s * NS_PER_S)),
                   sim=sim or SimParams())


def odom_rate(world: World, given: float | None, scan_hz: float) -> float:
    """The odometry tick [Hz] of a run of ``world``: ``given`` when set; else the scan rate
    for a fleet without people, :data:`~common.drive.ODOM_HZ` otherwise (one robot; people
    take their steps on this tick). A fleet's planners read odometry only at the scan
    instants (the same samples at either rate: the same drive, bit for bit); the tick
    changes the meter's integration step and the outcome's time resolution, and the 50 Hz
    streams were three quarters of a fleet's messages (docs/performance.md "A fleet's
    odometry rate")."""
    if given is not None:
        return given
    return scan_hz if world.robots and not world.has_people else ODOM_HZ


class ContactEpisodes:
    """Debounce contacts into one event per (obstacle, contact episode)."""

    def __init__(self, gap_ns: int = COLLISION_GAP_NS):
        self.gap_ns = gap_ns
        self._last: dict[int, int] = {}   # obstacle index -> last time in contact [ns]

    def update(self, t_ns: int, obstacles: list[int]) -> list[int]:
        """Obstacles in contact at ``t_ns``; returns those starting a new episode."""
        new = [i for i in obstacles if i not in self._last or t_ns - self._last[i] > self.gap_ns]
        for i in obstacles:
            self._last[i] = t_ns
        return new


class WorldCore:
    """Simulated ROSbots on the lockstep time grid (see module doc).

    One robot (``world.robots`` empty): topics are plain (``sim/pose``), under the node's
    namespace. A fleet (``[[robots]]``): every robot in one physics world, its topics under
    its own name (``r1/sim/pose``), and an instant's lockstep is complete only when every
    robot's planner answered the scan (:meth:`command`).
    """

    def __init__(self, world: World, seed: int, config: WorldConfig | None = None):
        self.config = cfg = config or WorldConfig()
        self.world = world
        fleet = world.robots
        self.names = [r.name for r in fleet] or [""]
        starts = [tuple(r.start) for r in fleet] or None
        self.sim = SimBase(world, seed, cfg.sim, starts)
        n = len(self.names)
        self.gates = [CommandGate(cfg.limits) for _ in range(n)]
        self.gate = self.gates[0]
        self.monitors = [ContactEpisodes() for _ in range(n)]
        self.collisions = self.monitors[0]
        self.collision_counts = [0] * n
        self._pending: list[list[Event]] = [[] for _ in range(n)]
        self._watchdog_stopped = [False] * n
        self._answered: set[int] = set()          # robots whose command answers this scan
        self._index = {name: i for i, name in enumerate(self.names)}
        self.crowd = None
        if world.has_people:   # people who react or replayed (common/crowd.py), in the physics
            from common.crowd import Crowd  # pyrvo / pysocialforce: only with people

            self.crowd = Crowd(world.people, world, seed)
            self.sim.add_people(self.crowd.body_radii)
            self.sim.place_people(self.crowd.positions, self.crowd.present)

    @property
    def collision_count(self) -> int:
        return sum(self.collision_counts)

    @property
    def t_ns(self) -> int:
        return self.sim.t_ns

    def is_scan_instant(self) -> bool:
        return self.t_ns % self.config.scan_period_ns == 0

    def last_scan_instant(self) -> int:
        """The latest scan instant <= t [ns]."""
        return self.t_ns - self.t_ns % self.config.scan_period_ns

    def topic(self, i: int, suffix: str) -> str:
        """Robot ``i``'s topic: ``suffix`` alone, or ``<name>/<suffix>`` in a fleet."""
        return f"{self.names[i]}/{suffix}" if self.names[i] else suffix

    def outputs(self) -> list[tuple[str, object]]:
        """(topic, message) to publish at instant t, in protocol order, robot after robot
        (a fleet's robots first get ``sim/bodies`` at a scan instant); clears pending events."""
        t = self.t_ns
        out: list[tuple[str, object]] = []
        # the LiDARs of a [[robots]] or [[people]] world wait for it (nodes/lidar_sim)
        scan = (bool(self.world.robots) or self.crowd is not None) and self.is_scan_instant()
        odoms = [self.sim.odometry(t, i) for i in range(len(self.names))]
        if self.crowd is not None:
            out.append(("sim/people", self._people(t)))
        if self.is_scan_instant():
            self._answered = set()
        # every robot's velocity read once per instant, not once per robot that sees it
        vel = [self.sim.velocity(j) for j in range(len(self.names))] if scan else []
        for i, odom in enumerate(odoms):
            if scan:
                out.append((self.topic(i, "sim/bodies"), self._bodies(t, i, odoms, vel)))
            out += [(self.topic(i, "sim/pose"), odom), (self.topic(i, "odom"), odom),
                    (self.topic(i, "wheels"), self.sim.wheel_states(t, i)),
                    (self.topic(i, "clock"), Clock(stamp_ns=t))]
            out += [(self.topic(i, "events"), e) for e in self._pending[i]]
            self._pending[i] = []
        return out

    def _bodies(self, t: int, i: int, odoms: list, vel: list) -> Bodies:
        """What robot ``i``'s LiDAR sees move at ``t``: every other robot (``odoms``, ``vel``:
        every robot's pose and world-frame velocity at ``t``), every person."""
        others = [j for j in range(len(self.names)) if j != i]
        xy = self.crowd.positions if self.crowd is not None else np.zeros((0, 2))
        pv = self.crowd.velocities if self.crowd is not None else np.zeros((0, 2))
        radii = self.crowd.radii if self.crowd is not None else ()
        rv = [vel[j] for j in others]
        return Bodies(stamp_ns=t, robots=tuple(self.names[j] for j in others),
                      robot_x=tuple(odoms[j].x for j in others),
                      robot_y=tuple(odoms[j].y for j in others),
                      robot_yaw=tuple(odoms[j].yaw for j in others),
                      person_x=tuple(float(v) for v in xy[:, 0]),
                      person_y=tuple(float(v) for v in xy[:, 1]),
                      person_radius=tuple(float(r) for r in radii),
                      robot_vx=tuple(float(a) for a, _ in rv),
                      robot_vy=tuple(float(b) for _, b in rv),
                      person_vx=tuple(float(a) for a in pv[:, 0]),
                      person_vy=tuple(float(a) for a in pv[:, 1]))

    def _people(self, t: int) -> People:
        crowd = self.crowd
        xy, v = crowd.positions, crowd.velocities
        return People(stamp_ns=t, x=tuple(float(a) for a in xy[:, 0]),
                      y=tuple(float(a) for a in xy[:, 1]), vx=tuple(float(a) for a in v[:, 0]),
                      vy=tuple(float(a) for a in v[:, 1]),
                      radius=tuple(float(r) for r in crowd.radii))

    def command(self, twist: Twist, robot: str = "") -> bool:
        """Apply robot ``robot``'s command; True once it completes the lockstep of this
        instant: every robot has answered the scan of ``t`` (``stamp_ns == t``)."""
        t = self.t_ns
        i = self._index.get(robot)
        if i is None:
            return False
        self.gates[i].command(twist.v, twist.w, min(twist.stamp_ns, t))
        if twist.stamp_ns == t and self.is_scan_instant():
            self._answered.add(i)
            return len(self._answered) == len(self.names)
        return False

    def advance(self) -> None:
        """Step the physics to the next publication instant."""
        step_ns = self.config.sim.step_ns
        n = len(self.names)
        if self.crowd is not None:   # people take the instant's step, seeing the robots now
            robots = [(*self.sim.pose(i)[:2], *self.sim.velocity(i)) for i in range(n)]
            self.crowd.step(self.config.odom_period_ns / NS_PER_S, robots)
            self.sim.place_people(self.crowd.positions, self.crowd.present)
        for _ in range(self.config.odom_period_ns // step_ns):
            t = self.sim.t_ns
            for i in range(n):
                v, w, stopped = self.gates[i].output(t, step_ns * 1e-9)
                if stopped and not self._watchdog_stopped[i]:
                    self._event(i, t, "watchdog_stop",
                                f"no fresh cmd_vel for {self.config.limits.watchdog_ns / 1e9:g} s; "
                                "stopping")
                self._watchdog_stopped[i] = stopped
                self.sim.set_twist(v, w, i)
            self.sim.step()
            for i in range(n):
                self._check_contacts(i)

    def _check_contacts(self, i: int) -> None:
        contacts = self.sim.contacts(i)
        if not contacts:
            return
        t = self.sim.t_ns
        n = len(self.names)   # monitor keys: obstacles >= 0, robots -1.., people after them
        keys = [c.obstacle if c.robot < 0 and c.person < 0 else
                -1 - c.robot if c.robot >= 0 else -1 - n - c.person for c in contacts]
        new = set(self.monitors[i].update(t, keys))
        for c, key in zip(contacts, keys, strict=True):
            if key in new:
                self.collision_counts[i] += 1
                what = (f"robot {self.names[c.robot]}" if c.robot >= 0 else
                        f"person {c.person}, {self._cause(i, c.person)}" if c.person >= 0 else
                        f"obstacle {c.obstacle} ({self.world.obstacles[c.obstacle].kind})")
                self._event(i, t, "collision", what, c.x, c.y)

    def _cause(self, i: int, k: int) -> str:
        """Who caused robot ``i``'s contact with person ``k`` (common/crowd_social.py)."""
        from common.crowd_social import collision_cause

        by = collision_cause(self.sim.pose(i)[:2], self.sim.velocity(i),
                             self.crowd.positions[k], self.crowd.velocities[k])
        return f"caused by the {by}"

    def _event(self, i: int, t_ns: int, kind: str, detail: str, x: float = float("nan"),
               y: float = float("nan")) -> None:
        self._pending[i].append(Event(stamp_ns=t_ns, kind=kind, source=SOURCE, detail=detail,
                                      x=x, y=y))

    def close(self) -> None:
        self.sim.close()

    def __enter__(self) -> WorldCore:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
