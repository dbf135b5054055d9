"""The ROSbot 2.0 PRO battery: a 3S pack of 18650 Li-ion cells (docs/architecture.md "The robot"; docs/energy.md).

Pure maths, no transport. The pack is modelled as an open-circuit voltage source
that follows the state of charge, in series with an internal resistance::

    V_terminal = OCV(SoC) - I * R_pack

Drawing a power P [W] from the terminals over dt [s] needs the current I that solves
``P = (OCV - I R) I``, i.e. ``R I^2 - OCV I + P = 0``. The physical (smaller) root is
computed in the cancellation-free form ``I = 2 P / (OCV + sqrt(OCV^2 - 4 R P))``
(exact, also for P = 0, R = 0 and P < 0 = charging). Above the pack's maximum
power ``OCV^2 / (4 R)`` no current delivers P: the pack then gives its maximum
(I = OCV / 2R) and :attr:`Battery.overloads` counts it.

Integration is explicit Euler: OCV is taken at the SoC at the start of the interval
and P, I are constant over it. Charge [mAh] = I dt / 3.6; energy [J] = V I dt (at the
terminals, i.e. P dt); SoC falls by the charge over the capacity (coulomb counting).
"""

from __future__ import annotations

import math
from bisect import bisect_right
from dataclasses import dataclass
from typing import ClassVar

from common.errors import PapfError
from common.params import Spec, check_all, integer, num, pos


class EnergyError(PapfError, ValueError):
    """An energy-meter input or setting that cannot be used (names the value and what is valid)."""


# Open-circuit voltage of one NCR18650-class (Panasonic NCA, 3400-3500 mAh) cell at 25 °C,
# rested, versus state of charge. ASSUMPTION: representative values rounded from published
# low-rate (about C/20) OCV-SoC curves of NCR18650B/GA cells; about ±30 mV. 0 % is set at
# 3.00 V (the ROSbot manual: "shall not be discharged below 3.0 V per cell"), 100 % at
# 4.20 V (end of CC/CV charge). The manual's lowest working voltage, 3.2 V, is ~3.6 % SoC.
CELL_OCV_SOC = (0.00, 0.05, 0.10, 0.20, 0.30, 0.40, 0.50, 0.60, 0.70, 0.80, 0.90, 0.95, 1.00)
CELL_OCV_V = (3.000, 3.280, 3.420, 3.550, 3.620, 3.680, 3.740, 3.820, 3.910, 3.990, 4.080, 4.140,
              4.200)

CELLS_SERIES = 3               # [-] 3S pack (Husarion ROSbot manual)
CELL_CAPACITY_MAH = 3500.0     # [mAh] XTAR 18650-350PCM 3500 mAh (PAPF paper IV-C)
# [ohm] per cell, ASSUMPTION: DC internal resistance of an NCR18650GA-class cell (~50 mOhm;
# datasheet AC impedance is ~35 mOhm at 1 kHz) + protection circuit of a "PCM" protected cell
# (~20 mOhm) + holder contacts (~10 mOhm).
CELL_RESISTANCE_OHM = 0.080
INITIAL_SOC = 1.0              # [-] the paper starts every run on freshly charged cells
S_PER_H = 3600.0               # [s/h]


def cell_ocv(soc: float) -> float:
    """Open-circuit voltage [V] of one cell at state of charge ``soc`` (0..1, clamped).

    Linear interpolation in the table, in plain floats (the meter runs this 50 times per
    sim second): the same operations, in the same order, as ``numpy.interp`` — an exact
    knot gives its voltage, otherwise ``slope * (soc - x_j) + y_j`` with ``slope =
    (y_j+1 - y_j) / (x_j+1 - x_j)`` — so the result is bit for bit numpy's (tested).
    """
    x = min(max(soc, 0.0), 1.0)
    if x != x:
        return x
    j = bisect_right(CELL_OCV_SOC, x) - 1            # CELL_OCV_SOC[j] <= x < CELL_OCV_SOC[j + 1]
    if j >= len(CELL_OCV_SOC) - 1 or CELL_OCV_SOC[j] == x:
        return CELL_OCV_V[j]
    x0, x1, y0, y1 = CELL_OCV_SOC[j], CELL_OCV_SOC[j + 1], CELL_OCV_V[j], CELL_OCV_V[j + 1]
    return (y1 - y0) / (x1 - x0) * (x - x0) + y0


@dataclass(frozen=True)
class PackParams:
    """Battery pack settings (each settable with ``--set name=value``)."""

    cells_series: int = CELLS_SERIES                   # [-]
    capacity_mAh: float = CELL_CAPACITY_MAH            # [mAh] series pack = one cell's capacity
    cell_resistance_ohm: float = CELL_RESISTANCE_OHM  # [ohm]
    initial_soc: float = INITIAL_SOC                   # [-] 0..1

    SPECS: ClassVar[dict[str, Spec]] = {
        "cells_series": integer(1, 100), "capacity_mAh": pos(1e6, "mAh"),
        "cell_resistance_ohm": num(0.0, 10.0, "ohm"), "initial_soc": num(0.0, 1.0),
    }

    def __post_init__(self) -> None:
        check_all(self, self.SPECS)

    @property
    def resistance_ohm(self) -> float:
        """Pack internal resistance [ohm] (cells in series)."""
        return self.cells_series * self.cell_resistance_ohm


@dataclass(frozen=True)
class Draw:
    """What one :meth:`Battery.draw` step delivered."""

    current_A: float   # [A] positive = discharge
    voltage_V: float   # [V] terminal voltage during the step
    power_W: float     # [W] delivered at the terminals (= the request unless overloaded)


def solve_current(power_W: float, ocv_V: float, resistance_ohm: float) -> tuple[float, bool]:
    """Current [A] that delivers ``power_W`` from a source ``ocv_V`` behind ``resistance_ohm``.

    Returns ``(current, overloaded)``; when overloaded the current is the maximum-power
    current ``ocv / 2R``.
    """
    disc = ocv_V * ocv_V - 4.0 * resistance_ohm * power_W
    if disc < 0.0:
        return ocv_V / (2.0 * resistance_ohm), True
    return 2.0 * power_W / (ocv_V + math.sqrt(disc)), False


class Battery:
    """A 3S Li-ion pack that integrates the charge and energy it delivers."""

    def __init__(self, params: PackParams | None = None):
        self.params = params or PackParams()
        self.soc = self.params.initial_soc        # [-]
        self.charge_used_mAh = 0.0                 # [mAh] since start (negative if regenerated)
        self.energy_J = 0.0                        # [J] at the terminals since start
        self.overloads = 0                         # steps where the power asked was above the max

    def ocv(self) -> float:
        """Pack open-circuit voltage [V] at the present SoC."""
        return self.params.cells_series * cell_ocv(self.soc)

    def draw(self, power_W: float, dt_s: float, measured_voltage_V: float | None = None) -> Draw:
        """Deliver ``power_W`` for ``dt_s`` seconds; update charge, energy and SoC.

        With ``measured_voltage_V`` (a real robot's voltage reading) the current is
        simply ``P / V_measured`` and the model's voltage is not used.
        """
        if not math.isfinite(power_W):
            raise EnergyError(f"power {power_W!r} W is not finite")
        if not (dt_s >= 0.0 and math.isfinite(dt_s)):
            raise EnergyError(f"time step {dt_s!r} s must be finite and >= 0")
        if measured_voltage_V is not None:
            current = power_W / measured_voltage_V
            voltage = measured_voltage_V
        else:
            ocv = self.ocv()
            current, overloaded = solve_current(power_W, ocv, self.params.resistance_ohm)
            voltage = ocv - current * self.params.resistance_ohm
            self.overloads += overloaded
        delivered = voltage * current
        charge_As = current * dt_s
        self.charge_used_mAh += charge_As / S_PER_H * 1000.0
        self.energy_J += delivered * dt_s
        capacity_As = self.params.capacity_mAh / 1000.0 * S_PER_H
        self.soc = min(max(self.soc - charge_As / capacity_As, 0.0), 1.0)
        return Draw(current, voltage, delivered)
