"""Electrical power drawn by the ROSbot 2.0 PRO, from the messages the base driver publishes.

Two models (docs/energy.md; every constant below has a unit and a source or a stated
ASSUMPTION; docs/energy.md discusses them):

- :class:`PaperModel` — PAPF paper, section II-A, eq. (6) (after Liu & Sun, AIM 2012)::

      E = ∫ (m v a + I ω β + (2 f_v / r) v + B) dt + P_s t

  a, β come from differencing successive odometry samples. Over an interval the kinetic
  terms use the midpoint speed, so ``m v a dt = Δ(½ m v²)`` exactly (also in reverse).
  No regeneration (default): each kinetic term is clamped at 0 — braking energy is lost,
  not returned. Friction uses |v| (it dissipates in both directions), averaged over the
  interval. As printed, f_v multiplies v (not v²): with power in W it is a torque [N·m]
  per side, a speed-independent friction torque. B is applied only while the robot moves
  (eq. (6) integrates it over a run in which the robot is moving).
- :class:`MotorModel` — per wheel, the DC gear motor's electrical power: mechanical
  power at the motor shaft τ_m ω_m, copper loss (τ_m / k_t)² R and the motor's no-load
  loss k_t I_0 |ω_m|, with τ_m from the wheel torque through the gearbox (ratio G,
  efficiency η). Negative (generating) wheel power is clamped at 0 unless regeneration
  is allowed. Plus the same electronics power P_s. Each interval uses the mean of its
  two end samples (trapezoid).

Both: ``update(odom, wheels) -> mean electrical power [W]`` over the interval from the
previous sample's stamp to this one (the first sample: the power at that instant).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import ClassVar

from common.errors import ConfigError
from common.params import FLAG, Spec, check_all, check_value, num, pos, unknown_name
from common.robot import (
    MASS_KG,
    WHEEL_RADIUS_M,
    YAW_INERTIA_KGM2,
)
from schemas import Odometry, WheelStates

from .battery import EnergyError

# -- robot (Husarion ROSbot 2.0 PRO specs, docs/architecture.md "The robot") ------------------------------------
# mass, body, yaw inertia, wheel radius, top speed: common/robot.py
GRAVITY_M_S2 = 9.81             # [m/s^2]

# -- drive train -------------------------------------------------------------------------------
GEAR_RATIO = 34.014             # [-] motor turns per wheel turn (husarion/rosbot-stm32-firmware,
                                #     rosbot_kinematics.h GEAR_RATIO)
GEAR_EFFICIENCY = 0.80          # [-] ASSUMPTION: multi-stage spur gearbox of a 25 mm gear motor
WINDING_RESISTANCE_OHM = 2.1    # [ohm] ASSUMPTION: 12 V / ~5.6 A stall current of a 25 mm,
                                #       12 V brushed gear motor of this class
NO_LOAD_CURRENT_A = 0.2         # [A] ASSUMPTION: typical no-load current of such a motor
# ASSUMPTION: the top speed is reached at the 3S nominal voltage (NOMINAL_VOLTAGE_V)
# [N m/A] = [V s/rad], derived: the motor reaches TOP_SPEED at NOMINAL_VOLTAGE with no load,
# k = (V - I_0 R) / (G v_top / r) = (11.1 - 0.42) / 1000.4
TORQUE_CONSTANT_NM_A = 0.0107

# -- electronics -------------------------------------------------------------------------------
UP_BOARD_W = 5.0                # [W] ASSUMPTION: UP Board (Atom x5-Z8350) running ROS + Wi-Fi
LIDAR_W = 2.5                   # [W] ASSUMPTION: RPLIDAR A3 spinning, 5 V x ~0.5 A
CORE2_W = 1.0                   # [W] ASSUMPTION: CORE2 (STM32F4, IMU, encoders, driver idle)
CAMERA_IDLE_W = 0.5             # [W] ASSUMPTION: Orbbec Astra powered, streams off
DCDC_EFFICIENCY = 0.90          # [-] ASSUMPTION: battery -> 5 V/3.3 V converters
P_S_W = (UP_BOARD_W + LIDAR_W + CORE2_W + CAMERA_IDLE_W) / DCDC_EFFICIENCY   # = 10.0 W

# -- paper model friction ----------------------------------------------------------------------
ROLLING_RESISTANCE = 0.03       # [-] ASSUMPTION: rubber tyres on a hard indoor floor
# [N m] per side (2 motors), chosen to match the motor model's straight-line friction: the
# motors' no-load loss (k_t I_0 G at the wheel) + rolling resistance through the gearbox.
F_V_NM = (2 * TORQUE_CONSTANT_NM_A * NO_LOAD_CURRENT_A * GEAR_RATIO
          + ROLLING_RESISTANCE * MASS_KG * GRAVITY_M_S2 * WHEEL_RADIUS_M / (2 * GEAR_EFFICIENCY))
B_W = 0.5                       # [W] ASSUMPTION: breakaway friction + motor-driver switching
                                #     losses while driving
MOVING_V_M_S = 1e-3             # [m/s] |v| above this counts as moving (for B)
MOVING_W_RAD_S = 1e-2           # [rad/s] |w| above this counts as moving (for B)


# Declared type and valid range of every model constant (common.params); the dataclasses
# check themselves on construction, --set values are checked as they are parsed.
PAPER_SPECS: dict[str, Spec] = {
    "mass_kg": pos(1000.0, "kg"), "yaw_inertia_kgm2": pos(1000.0, "kg m^2"),
    "wheel_radius_m": pos(1.0, "m"), "f_v_Nm": num(0.0, 100.0, "N m"),
    "b_W": num(0.0, 1000.0, "W"), "p_s_W": num(0.0, 1000.0, "W"),
    "b_while_moving_only": FLAG, "regeneration": FLAG,
}
MOTOR_SPECS: dict[str, Spec] = {
    "gear_ratio": pos(1000.0), "gear_efficiency": pos(1.0),
    "torque_constant_NmA": pos(10.0, "N m/A"), "winding_resistance_ohm": num(0.0, 100.0, "ohm"),
    "no_load_current_A": num(0.0, 100.0, "A"), "p_s_W": num(0.0, 1000.0, "W"),
    "regeneration": FLAG,
}


@dataclass(frozen=True)
class PaperParams:
    """Constants of eq. (6); each settable with ``--set name=value``."""

    SPECS: ClassVar[dict[str, Spec]] = PAPER_SPECS

    mass_kg: float = MASS_KG
    yaw_inertia_kgm2: float = YAW_INERTIA_KGM2
    wheel_radius_m: float = WHEEL_RADIUS_M
    f_v_Nm: float = F_V_NM
    b_W: float = B_W
    p_s_W: float = P_S_W
    b_while_moving_only: bool = True
    regeneration: bool = False

    def __post_init__(self) -> None:
        check_all(self, PAPER_SPECS)


@dataclass(frozen=True)
class MotorParams:
    """Constants of the DC gear-motor model; each settable with ``--set name=value``."""

    SPECS: ClassVar[dict[str, Spec]] = MOTOR_SPECS

    gear_ratio: float = GEAR_RATIO
    gear_efficiency: float = GEAR_EFFICIENCY
    torque_constant_NmA: float = TORQUE_CONSTANT_NM_A
    winding_resistance_ohm: float = WINDING_RESISTANCE_OHM
    no_load_current_A: float = NO_LOAD_CURRENT_A
    p_s_W: float = P_S_W
    regeneration: bool = False

    def __post_init__(self) -> None:
        check_all(self, MOTOR_SPECS)


class PaperModel:
    """PAPF eq. (6) power from successive odometry samples (wheels are not used)."""

    name = "paper"

    def __init__(self, params: PaperParams | None = None):
        self.params = params or PaperParams()
        self._prev: Odometry | None = None
        self.terms: dict[str, float] = {}   # last interval's terms [W], for inspection

    def update(self, odom: Odometry, wheels: WheelStates | None = None) -> float:
        p = self.params
        prev = self._prev or odom
        dt = _dt_s(prev.stamp_ns, odom.stamp_ns) if self._prev else 0.0
        self._prev = odom
        # ½ m (v1² - v0²) / dt == m * midpoint(v) * (v1 - v0) / dt: exact kinetic-energy change
        lin = p.mass_kg * (odom.v**2 - prev.v**2) / (2.0 * dt) if dt else 0.0
        rot = p.yaw_inertia_kgm2 * (odom.w**2 - prev.w**2) / (2.0 * dt) if dt else 0.0
        if not p.regeneration:
            lin, rot = max(lin, 0.0), max(rot, 0.0)
        speed = 0.5 * (abs(odom.v) + abs(prev.v))
        moving = max(abs(odom.v), abs(prev.v)) > MOVING_V_M_S or \
            max(abs(odom.w), abs(prev.w)) > MOVING_W_RAD_S
        self.terms = {
            "m_v_a": lin,
            "I_w_beta": rot,
            "viscous": 2.0 * p.f_v_Nm / p.wheel_radius_m * speed,
            "B": p.b_W if (moving or not p.b_while_moving_only) else 0.0,
            "P_s": p.p_s_W,
        }
        return math.fsum(self.terms.values())


def wheel_power(torque_Nm: float, speed_rad_s: float, p: MotorParams) -> float:
    """Electrical power [W] one motor draws to apply ``torque_Nm`` to a wheel at ``speed_rad_s``.

    Motoring (τω >= 0) the motor supplies τ / (G η); back-driven (τω < 0) the gearbox
    losses help, so the motor sees τ η / G. Electrical power = V I with V = k ω_m + I R and
    I = τ_m / k, i.e. τ_m ω_m + (τ_m / k)² R, plus the no-load loss k I_0 |ω_m|.
    """
    omega_m = p.gear_ratio * speed_rad_s
    if torque_Nm * speed_rad_s >= 0.0:
        tau_m = torque_Nm / (p.gear_ratio * p.gear_efficiency)
    else:
        tau_m = torque_Nm * p.gear_efficiency / p.gear_ratio
    current = tau_m / p.torque_constant_NmA
    power = (tau_m * omega_m + current * current * p.winding_resistance_ohm
             + p.torque_constant_NmA * p.no_load_current_A * abs(omega_m))
    return power if p.regeneration else max(power, 0.0)


class MotorModel:
    """Sum of the four motors' electrical power (from ``wheels``) plus electronics P_s."""

    name = "motor"

    def __init__(self, params: MotorParams | None = None):
        self.params = params or MotorParams()
        self._prev_stamp: int | None = None
        self._prev_wheels_W = 0.0
        self.terms: dict[str, float] = {}

    def update(self, odom: Odometry | None, wheels: WheelStates) -> float:
        if len(wheels.speed) != len(wheels.torque) or not wheels.speed:
            raise EnergyError(f"wheels at {wheels.stamp_ns} ns: {len(wheels.speed)} speeds and "
                              f"{len(wheels.torque)} torques (need one of each per wheel, >= 1)")
        now = math.fsum(wheel_power(t, s, self.params)
                        for t, s in zip(wheels.torque, wheels.speed, strict=True))
        if self._prev_stamp is not None:
            _dt_s(self._prev_stamp, wheels.stamp_ns)   # checks the order
            mean = 0.5 * (self._prev_wheels_W + now)
        else:
            mean = now
        self._prev_stamp, self._prev_wheels_W = wheels.stamp_ns, now
        self.terms = {"wheels": mean, "P_s": self.params.p_s_W}
        return mean + self.params.p_s_W


MODELS = {"paper": (PaperModel, PaperParams), "motor": (MotorModel, MotorParams)}
# the one default of the whole stack: the sim and laptop profiles, papf run, experiments, the
# meter and the report (the motor model needs wheel torques: the rosbot driver estimates them)
DEFAULT_MODEL = "motor"


def make_model(name: str, settings: Mapping[str, object] | None = None):
    """A fresh model by name, with settings overriding its default constants."""
    if name not in MODELS:
        raise ConfigError(f"energy model {name!r} is not one of {sorted(MODELS)}")
    cls, params_cls = MODELS[name]
    return cls(build_params(params_cls, settings or {}))


def setting_names(params_cls) -> tuple[str, ...]:
    return tuple(f.name for f in dataclasses.fields(params_cls))


def build_params(params_cls, settings: Mapping[str, object]):
    """``params_cls(**settings)`` with every value checked against its declared range."""
    specs = params_cls.SPECS
    values = {}
    for name, value in settings.items():
        if name not in specs:
            raise unknown_name(name, specs)
        values[name] = check_value(name, value, specs[name])
    return params_cls(**values)


def _dt_s(prev_ns: int, now_ns: int) -> float:
    if now_ns <= prev_ns:
        raise EnergyError(f"stamp {now_ns} ns is not after the previous sample's {prev_ns} ns")
    return (now_ns - prev_ns) * 1e-9
