"""Energy meter core: pairs ``odom(t)`` with ``wheels(t)``, integrates power, reports the pack.

Pure (no transport). :class:`EnergyMeter` is a deterministic function of the message
sequence it is fed: the same messages (live, or replayed from a recording to re-meter
a run with another model) give bit-identical :class:`~schemas.BatteryState` results.

Pairing: messages of the two topics may interleave in any order; a pair completes when
both messages with the same ``stamp_ns`` have arrived, and is processed at once. Each
topic is expected in stamp order (one publisher); a pair older than or equal to the last
processed stamp is dropped (counted in :attr:`EnergyMeter.stale`), and a half pair left
behind by a newer completed pair is discarded (a lost message: the next interval then
simply spans the gap).

Integration: pair k (stamp t_k) gives the model's mean power P_k over (t_{k-1}, t_k];
the pack delivers P_k for t_k - t_{k-1} (see battery.py). The first pair only reports.
This emulates the paper's measurement (IV-C): the charge drawn from the pack, in mAh,
as the XTAR charger reported it when refilling the cells.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from common.errors import ConfigError
from schemas import BatteryState, Odometry, WheelStates

from .battery import Battery, EnergyError, PackParams
from .models import MODELS, build_params, make_model, setting_names

MAX_PENDING = 250                    # [-] unmatched messages kept per topic (5 s at 50 Hz)
MEASURED_VOLTAGE_MAX_AGE_NS = 5_000_000_000   # [ns] a measured voltage older than this is ignored


def split_settings(model_name: str, settings: Mapping[str, object]) -> tuple[dict, dict]:
    """Split ``name=value`` settings into (pack settings, model settings)."""
    if model_name not in MODELS:
        make_model(model_name)   # raises the ConfigError naming the valid models
    pack_names, model_names = setting_names(PackParams), setting_names(MODELS[model_name][1])
    unknown = sorted(set(settings) - set(pack_names) - set(model_names))
    if unknown:
        raise ConfigError(f"unknown setting(s) {', '.join(map(repr, unknown))} for the "
                          f"{model_name} model; valid: {', '.join(pack_names + model_names)}")
    pack = {k: v for k, v in settings.items() if k in pack_names}
    model = {k: v for k, v in settings.items() if k not in pack_names}
    return pack, model


class EnergyMeter:
    """Meter electrical energy from odometry and wheel states (see module doc).

    ``EnergyMeter("motor", {"initial_soc": 0.8, "p_s_W": 9.0})``; settings are the fields of
    :class:`~nodes.energy_meter.battery.PackParams` and of the model's params class.
    """

    def __init__(self, model_name: str = "motor", params: Mapping[str, object] | None = None):
        pack, model = split_settings(model_name, params or {})
        self.model_name = model_name
        self.model = make_model(model_name, model)
        self.battery = Battery(build_params(PackParams, pack))
        self._odom: dict[int, Odometry] = {}
        self._wheels: dict[int, WheelStates] = {}
        self._last_ns: int | None = None
        self._measured: tuple[float, int] | None = None   # (voltage [V], stamp [ns])
        self.stale = 0          # pairs dropped as older than the last processed one
        self.discarded = 0      # half pairs dropped (their partner never came)

    def resume(self, charge_mAh: float, energy_J: float, soc: float, stamp_ns: int) -> None:
        """Go on with an account another meter kept up to ``stamp_ns`` (a laptop that died and
        came back, ``--resume``): the first pair after it integrates its power over the whole
        gap, which the robot spent standing (its watchdog stopped it), so the gap is metered
        at standstill power."""
        for name, value in (("charge_mAh", charge_mAh), ("energy_J", energy_J), ("soc", soc)):
            if not math.isfinite(value):
                raise ConfigError(f"--resume: {name} {value!r} is not a finite number")
        if not 0.0 <= soc <= 1.0:
            raise ConfigError(f"--resume: soc {soc!r} is outside [0, 1]")
        self.battery.charge_used_mAh, self.battery.energy_J = float(charge_mAh), float(energy_J)
        self.battery.soc = float(soc)
        self._last_ns = int(stamp_ns) if stamp_ns >= 0 else None

    # -- input ------------------------------------------------------------------------------
    def feed(self, msg: Odometry | WheelStates) -> BatteryState | None:
        """Take one message; return the pack state if it completed a pair, else None."""
        if isinstance(msg, Odometry):
            mine, other = self._odom, self._wheels
        elif isinstance(msg, WheelStates):
            mine, other = self._wheels, self._odom
        else:
            raise EnergyError(f"cannot meter a {type(msg).__name__}; feed Odometry or WheelStates")
        t = msg.stamp_ns
        if self._last_ns is not None and t <= self._last_ns:
            self.stale += 1
            return None
        mine[t] = msg
        if t not in other:
            self._trim(mine)
            return None
        odom, wheels = self._odom.pop(t), self._wheels.pop(t)
        self._drop_older_than(t)
        return self._step(odom, wheels)

    def set_measured_voltage(self, voltage_V: float, stamp_ns: int) -> None:
        """A real robot's pack voltage; used instead of the model's while fresh (5 s)."""
        if not (math.isfinite(voltage_V) and voltage_V > 0.0):
            raise EnergyError(f"measured voltage {voltage_V!r} V must be a finite number > 0")
        self._measured = (float(voltage_V), int(stamp_ns))

    # -- internals --------------------------------------------------------------------------
    def _step(self, odom: Odometry, wheels: WheelStates) -> BatteryState:
        t = odom.stamp_ns
        power = self.model.update(odom, wheels)
        dt = 0.0 if self._last_ns is None else (t - self._last_ns) * 1e-9
        self._last_ns = t
        draw = self.battery.draw(power, dt, self._measured_voltage(t))
        b = self.battery
        return BatteryState(stamp_ns=t, voltage=draw.voltage_V, current=draw.current_A,
                            power=draw.power_W, charge_used_mAh=b.charge_used_mAh,
                            energy_J=b.energy_J, soc=b.soc, model=self.model_name)

    def _measured_voltage(self, t: int) -> float | None:
        if self._measured is None:
            return None
        voltage, stamp = self._measured
        return voltage if abs(t - stamp) <= MEASURED_VOLTAGE_MAX_AGE_NS else None

    def _drop_older_than(self, t: int) -> None:
        for pending in (self._odom, self._wheels):
            for stamp in [s for s in pending if s < t]:
                del pending[stamp]
                self.discarded += 1

    def _trim(self, pending: dict) -> None:
        while len(pending) > MAX_PENDING:
            del pending[min(pending)]
            self.discarded += 1
