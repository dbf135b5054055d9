"""The simulated driver's pure core: sim time grid, command gate, physics, events.

No zenoh here. :class:`DriverCore` advances a :class:`~nodes.base_driver.sim.SimBase`
one publication instant at a time (docs/architecture.md "Time" and "Lockstep"):

- ``outputs()`` -> the messages of instant ``t``, in the protocol's order:
  ``sim/pose``, ``odom``, ``wheels``, ``clock``, then any ``events`` that happened
  since the previous instant (collision, watchdog_stop);
- ``command(twist)`` -> feeds the :class:`~nodes.base_driver.limits.CommandGate`
  (the command counts as issued at ``min(stamp, t)``) and says whether it is *the*
  answer to the scan of instant ``t`` (``stamp_ns == t``);
- ``advance()`` -> physics steps of 4 ms up to the next instant, the gate's
  rate-limited output applied at every step.

Collisions are debounced: one ``collision`` event per contact episode per obstacle;
an episode ends after :data:`COLLISION_GAP_NS` without contact.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from common.errors import ConfigError
from common.params import check_value
from common.units import NS_PER_S
from nodes.base_driver.limits import OPTIONS, CommandGate, RosbotLimits
from nodes.base_driver.sim import SimBase, SimParams
from schemas.messages import Clock, Event, Twist
from worlds import World

SOURCE = "base_driver"            # Event.source of this node's events
COLLISION_GAP_NS = 200_000_000    # [ns] contact-free time that ends a contact episode (assumption)


def period_ns(hz: float, what: str) -> int:
    """An exact integer period [ns] for a rate [Hz]; ConfigError if 1 s is not a whole number of ns periods."""
    if not (hz > 0) or hz != hz:
        raise ConfigError(f"{what} = {hz!r} Hz must be > 0")
    period = round(NS_PER_S / hz)
    if period * hz != NS_PER_S:
        raise ConfigError(f"{what} = {hz} Hz gives a period of {NS_PER_S / hz} ns, not an integer; "
                          "use a rate that divides 1e9 ns (e.g. 10, 20, 25, 50 Hz)")
    return period


@dataclass(frozen=True)
class DriverConfig:
    """Time grid and limits of the simulated driver."""

    odom_period_ns: int = 20_000_000     # [ns] sim/pose, odom, wheels, clock (50 Hz)
    scan_period_ns: int = 100_000_000    # [ns] lockstep instants (10 Hz, the RPLIDAR A3 rate)
    limits: RosbotLimits = field(default_factory=RosbotLimits)
    sim: SimParams = field(default_factory=SimParams)

    def __post_init__(self) -> None:
        step = self.sim.step_ns
        if self.odom_period_ns <= 0 or self.odom_period_ns % step:
            raise ConfigError(f"odometry period {self.odom_period_ns} ns must be a positive "
                              f"multiple of the {step} ns physics step")
        if self.scan_period_ns <= 0 or self.scan_period_ns % self.odom_period_ns:
            raise ConfigError(f"scan period {self.scan_period_ns} ns must be a positive multiple "
                              f"of the odometry period {self.odom_period_ns} ns")

    @classmethod
    def from_rates(cls, odom_hz: float = 50.0, scan_hz: float = 10.0, watchdog_s: float = 0.5,
                   sim: SimParams | None = None) -> DriverConfig:
        for name, value in (("odom_hz", odom_hz), ("scan_hz", scan_hz), ("watchdog", watchdog_s)):
            check_value(name, value, OPTIONS[name])
        return cls(odom_period_ns=period_ns(odom_hz, "odometry rate"),
                   scan_period_ns=period_ns(scan_hz, "scan rate"),
                   limits=RosbotLimits(watchdog_ns=round(watchdog_s * NS_PER_S)),
                   sim=sim or SimParams())


class CollisionMonitor:
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


class DriverCore:
    """Simulated ROSbot on the lockstep time grid (see module doc)."""

    def __init__(self, world: World, seed: int, config: DriverConfig | None = None):
        self.config = cfg = config or DriverConfig()
        self.world = world
        self.sim = SimBase(world, seed, cfg.sim)
        self.gate = CommandGate(cfg.limits)
        self.collisions = CollisionMonitor()
        self.collision_count = 0
        self._pending: list[Event] = []
        self._watchdog_stopped = False

    @property
    def t_ns(self) -> int:
        return self.sim.t_ns

    def is_scan_instant(self) -> bool:
        return self.t_ns % self.config.scan_period_ns == 0

    def last_scan_instant(self) -> int:
        """The latest scan instant <= t [ns]."""
        return self.t_ns - self.t_ns % self.config.scan_period_ns

    def outputs(self) -> list[tuple[str, object]]:
        """(topic, message) to publish at instant t, in protocol order; clears pending events."""
        t = self.t_ns
        odom = self.sim.odometry(t)
        out: list[tuple[str, object]] = [("sim/pose", odom), ("odom", odom),
                                         ("wheels", self.sim.wheel_states(t)),
                                         ("clock", Clock(stamp_ns=t))]
        out += [("events", e) for e in self._pending]
        self._pending = []
        return out

    def command(self, twist: Twist) -> bool:
        """Apply a command; True if it answers the scan of this instant (lockstep match)."""
        t = self.t_ns
        self.gate.command(twist.v, twist.w, min(twist.stamp_ns, t))
        return twist.stamp_ns == t and self.is_scan_instant()

    def advance(self) -> None:
        """Step the physics to the next publication instant."""
        step_ns = self.config.sim.step_ns
        for _ in range(self.config.odom_period_ns // step_ns):
            t = self.sim.t_ns
            v, w, stopped = self.gate.output(t, step_ns * 1e-9)
            if stopped and not self._watchdog_stopped:
                self._event(t, "watchdog_stop",
                            f"no fresh cmd_vel for {self.config.limits.watchdog_ns / 1e9:g} s; stopping")
            self._watchdog_stopped = stopped
            self.sim.set_twist(v, w)
            self.sim.step()
            self._check_contacts()

    def _check_contacts(self) -> None:
        contacts = self.sim.contacts()
        if not contacts:
            return
        t = self.sim.t_ns
        new = set(self.collisions.update(t, [c.obstacle for c in contacts]))
        for c in contacts:
            if c.obstacle in new:
                self.collision_count += 1
                kind = self.world.obstacles[c.obstacle].kind
                self._event(t, "collision", f"obstacle {c.obstacle} ({kind})", c.x, c.y)

    def _event(self, t_ns: int, kind: str, detail: str, x: float = float("nan"),
               y: float = float("nan")) -> None:
        self._pending.append(Event(stamp_ns=t_ns, kind=kind, source=SOURCE, detail=detail, x=x, y=y))

    def close(self) -> None:
        self.sim.close()

    def __enter__(self) -> DriverCore:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
