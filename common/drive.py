"""How a ROSbot takes a velocity command: the controller's gate and the arc it drives.

One gate for every ROSbot of the stack: the world simulator's robots
(``nodes/world_sim``), the real robot's base driver (``nodes/base_driver``), the ROSbot
emulator (``papf/robot/emulator.py``) and the offline runs (``papf/offline``), so a command
is limited alike wherever it goes. Pure Python (no pybullet, no zenoh).

:class:`CommandGate` does what the ROS 2 ``diff_drive_controller`` of the ROSbot does with
``/cmd_vel`` (docs/architecture.md "The robot", docs/architecture.md "Safety"):

1. non-finite ``v`` or ``w`` -> the whole command is treated as a stop (0, 0);
2. velocity clamp ``|v| <= v_max``, ``|w| <= w_max``;
3. watchdog: no fresh command for ``watchdog_ns`` (in the caller's time base, sim
   time in sim) -> the target becomes (0, 0) and ``stopped_by_watchdog`` is set;
4. acceleration rate limit towards the target (like the controller's
   ``SpeedLimiter``): ``|dv/dt| <= a_max``, ``|dw/dt| <= alpha_max``, so a watchdog
   stop decelerates at the limit too, as on the robot.
5. a late step (``speed_up_dt_max_s``, the real robot's driver: its loop stalled on a busy
   computer): slowing down may use the whole time since the last step, speeding up only
   ``speed_up_dt_max_s`` of it, so a stall never ends in a jump of speed — the robot keeps
   its limits, and a stop after the stall is not delayed by them. A step no longer than
   that takes rule 4 as it is, to the bit (the simulator's steps always do).

Usage: ``gate.command(v, w, t_ns)`` whenever a command arrives, then
``v, w, stopped = gate.output(t_ns, dt_s)`` every control step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

from common import robot
from common.errors import ConfigError
from common.params import SEED, Spec, arg_type, pos
from common.units import LOCKSTEP_TIMEOUT_S

ODOM_HZ = 50.0   # [Hz] the odometry tick of a robot, real or simulated (a fleet's: world_sim.core.odom_rate)

# Declared ranges of the drivers' options (common.params): the world simulator's and the
# ROSbot driver's command lines share them; checked when parsed and again when used.
# The watchdog is a safety setting: past 2 s a robot keeps driving on a lost command.
DRIVER_OPTIONS: dict[str, Spec] = {
    "odom_hz": pos(1000.0, "Hz"), "scan_hz": pos(100.0, "Hz"),
    "watchdog": pos(2.0, "s", safety=True), "lockstep_timeout": pos(60.0, "s"), "seed": SEED,
}
# The planner's and tracker's --pair-timeout: up to a second past the longest lockstep
# timeout (common.units.pair_timeout_s gives it beside a driver's)
PAIR_TIMEOUT: Spec = pos(DRIVER_OPTIONS["lockstep_timeout"].hi + 1.0, "s")


def add_driver_args(parser, simulator: bool = True) -> None:
    """The options of the world simulator, which the robot's driver takes too (one command
    line serves both: ``python -m nodes.base_driver --driver sim`` hands it to the simulator);
    ``simulator=False`` says which of them the robot leaves unused."""
    def opt(name: str):
        return arg_type("--" + name.replace("_", "-"), DRIVER_OPTIONS[name])

    sim = "" if simulator else " (the simulator's: unused on the robot)"
    parser.add_argument("--world", default="energy",
                        help="world name or .toml path (default energy)" + ("" if simulator else
                             ": its start is the robot's pose when a run starts"))
    parser.add_argument("--seed", type=opt("seed"), default=0, help="noise seed (default 0)" + sim)
    parser.add_argument("--realtime", action="store_true",
                        help="pace sim time to the wall clock and never wait for commands" + sim)
    parser.add_argument("--lockstep-timeout", type=opt("lockstep_timeout"),
                        default=LOCKSTEP_TIMEOUT_S, metavar="S",
                        help="wall seconds to wait for the cmd_vel of a scan "
                             f"(default {LOCKSTEP_TIMEOUT_S:g})" + sim)
    parser.add_argument("--scan-hz", type=opt("scan_hz"), default=10.0,
                        help="scan / lockstep rate (10)" + sim)
    parser.add_argument("--odom-hz", type=opt("odom_hz"), default=None if simulator else ODOM_HZ,
                        help="odometry, wheels and clock rate (50" + (
                            "; a fleet's without people: the scan rate, docs/performance.md \"A fleet's "
                            "odometry rate\")" if simulator else ")"))
    parser.add_argument("--watchdog", type=opt("watchdog"), default=0.5, metavar="S",
                        help="stop when no fresh command for S seconds (default 0.5)")
    parser.add_argument("--log-level", default="INFO")


@dataclass(frozen=True)
class RosbotLimits:
    """Command limits of the ROSbot 2.0 PRO (docs/architecture.md "The robot").

    Source: husarion/rosbot_ros ``rosbot_controller/config/.../diff_drive_controller.yaml``
    as summarised in docs/architecture.md "The robot": linear max 0.9 m/s (the yaml has 1.0; the design
    keeps a margin under the 1.25 m/s top speed), 1.0 m/s^2; angular 3.0 rad/s,
    4.0 rad/s^2; ``cmd_vel_timeout`` 0.5 s.
    """

    v_max: float = robot.V_MAX_M_S                # [m/s] |linear.x| limit
    w_max: float = robot.W_MAX_RAD_S              # [rad/s] |angular.z| limit
    a_max: float = robot.A_MAX_M_S2               # [m/s^2] linear acceleration limit
    alpha_max: float = robot.ALPHA_MAX_RAD_S2     # [rad/s^2] angular acceleration limit
    watchdog_ns: int = robot.CMD_VEL_TIMEOUT_NS   # [ns] cmd_vel_timeout

    def __post_init__(self) -> None:
        for name in ("v_max", "w_max", "a_max", "alpha_max"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ConfigError(f"RosbotLimits.{name} = {value!r} must be a finite number > 0")
        if not isinstance(self.watchdog_ns, int) or self.watchdog_ns <= 0:
            raise ConfigError(f"RosbotLimits.watchdog_ns = {self.watchdog_ns!r} must be an "
                              "integer number of nanoseconds > 0")


class GateOutput(NamedTuple):
    v: float                   # [m/s] command to apply now
    w: float                   # [rad/s]
    stopped_by_watchdog: bool  # the target is zero because no fresh command came in time


def _clamp(x: float, limit: float) -> float:
    return max(-limit, min(limit, x))


class CommandGate:
    """Clamp, rate-limit and watchdog a stream of (v, w) commands (see module doc)."""

    def __init__(self, limits: RosbotLimits | None = None, speed_up_dt_max_s: float | None = None):
        self.limits = limits or RosbotLimits()
        if speed_up_dt_max_s is not None and not (math.isfinite(speed_up_dt_max_s)
                                                  and speed_up_dt_max_s > 0):
            raise ConfigError(f"speed_up_dt_max_s = {speed_up_dt_max_s!r} must be a finite "
                              "number > 0 (or None)")
        self.speed_up_dt_max_s = speed_up_dt_max_s   # [s] module doc, rule 5
        self._target = (0.0, 0.0)
        self._last_cmd_ns: int | None = None
        self._out = (0.0, 0.0)
        self.rejected_nonfinite = 0     # commands turned into a stop because of nan/inf

    @property
    def last_command_ns(self) -> int | None:
        """Time of the freshest accepted command, or None before the first one."""
        return self._last_cmd_ns

    def command(self, v: float, w: float, t_ns: int) -> bool:
        """Take a new command valid from ``t_ns``; False (ignored) if older than the last one."""
        if self._last_cmd_ns is not None and t_ns < self._last_cmd_ns:
            return False
        if not (math.isfinite(v) and math.isfinite(w)):
            self.rejected_nonfinite += 1
            v, w = 0.0, 0.0
        lim = self.limits
        self._target = (_clamp(float(v), lim.v_max), _clamp(float(w), lim.w_max))
        self._last_cmd_ns = t_ns
        return True

    @property
    def last_output(self) -> tuple[float, float]:
        """The (v, w) of the last :meth:`output`: what the robot was last commanded."""
        return self._out

    def stop_time_s(self) -> float:
        """[s] the longest a stop at the limits takes from the last output."""
        v, w = self._out
        return max(abs(v) / self.limits.a_max, abs(w) / self.limits.alpha_max)

    def stopped_by_watchdog(self, t_ns: int) -> bool:
        """True when a command was once received but none is fresh at ``t_ns``."""
        return (self._last_cmd_ns is not None
                and t_ns - self._last_cmd_ns > self.limits.watchdog_ns)

    def output(self, t_ns: int, dt_s: float) -> GateOutput:
        """The rate-limited command for the control step of ``dt_s`` seconds starting at ``t_ns``."""
        lim = self.limits
        last = self._last_cmd_ns   # stopped_by_watchdog(t_ns), inline: called every physics step
        stopped = last is not None and t_ns - last > lim.watchdog_ns
        v_t, w_t = (0.0, 0.0) if stopped else self._target
        v0, w0 = self._out
        cap = self.speed_up_dt_max_s
        if cap is None or dt_s <= cap:
            dv, dw = lim.a_max * dt_s, lim.alpha_max * dt_s
            v = v0 + max(-dv, min(dv, v_t - v0))      # _clamp, inline
            w = w0 + max(-dw, min(dw, w_t - w0))
        else:   # a late step (rule 5)
            v = _late_ramp(v0, v_t, lim.a_max * dt_s, lim.a_max * cap)
            w = _late_ramp(w0, w_t, lim.alpha_max * dt_s, lim.alpha_max * cap)
        self._out = (v, w)
        return GateOutput(v, w, stopped)


def _late_ramp(x0: float, target: float, down: float, up: float) -> float:
    """``x0`` moved towards ``target`` after a late step: by up to ``down`` towards zero
    (slowing down) and by up to ``up`` (<= ``down``) away from it, either way (speeding up,
    also past zero into reverse). Written for ``x0 >= 0``; reverse is its mirror (negation is
    exact in floating point)."""
    if x0 < 0:
        return -_late_ramp(-x0, -target, down, up)
    lo = x0 - down if x0 - down >= 0 else -min(up, down - x0)
    return max(lo, min(x0 + up, target))


def unicycle(x: float, y: float, yaw: float, v: float, w: float, dt: float):
    """Exact integration of a unicycle with constant (v, w) over ``dt``: the arc it drives.

    The kinematics of every non-physics model of the ROSbot (the offline planner loop,
    the ROSbot emulator); yaw is not wrapped.
    """
    if abs(w) < 1e-9:
        return x + v * dt * math.cos(yaw), y + v * dt * math.sin(yaw), yaw
    yaw2 = yaw + w * dt
    return (x + v / w * (math.sin(yaw2) - math.sin(yaw)),
            y - v / w * (math.cos(yaw2) - math.cos(yaw)), yaw2)
