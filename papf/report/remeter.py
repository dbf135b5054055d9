"""Re-meter a recorded run: feed its ``odom``, ``wheels`` and ``battery/measured`` to a fresh
energy meter.

:class:`nodes.energy_meter.core.EnergyMeter` is a pure function of the message
sequence, so feeding the recorded messages in recorded (log-time) order with the model
and settings the live meter ran gives bit-identical
:class:`~schemas.BatteryState` figures (tests/e2e/test_report.py checks it on a real run);
another model or other settings re-meter the same motion (docs/energy.md).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from pathlib import Path

from common.errors import PapfError
from nodes.energy_meter.core import EnergyMeter
from papf.recording.rosbag import TopicMap, open_run
from schemas import BatteryState, BatteryVoltage, Odometry, WheelStates


class Remeter:
    """``Remeter("paper").feed(msg)`` for every odom/wheels message; ``.states`` = the outputs."""

    def __init__(self, model: str = "motor", params: Mapping[str, object] | None = None):
        self.meter = EnergyMeter(model, dict(params or {}))  # ConfigError on a bad model/setting
        self.states: list[BatteryState] = []
        self.rejected = 0  # messages the meter refused (the live node logs and drops them too)

    def feed(self, msg: Odometry | WheelStates) -> None:
        try:
            state = self.meter.feed(msg)
        except PapfError:
            self.rejected += 1
            return
        if state is not None:
            self.states.append(state)

    def measured(self, msg: BatteryVoltage) -> None:
        """A real robot's pack voltage: the meter uses it while fresh, as the live one does."""
        try:
            self.meter.set_measured_voltage(msg.voltage, msg.stamp_ns)
        except PapfError:
            self.rejected += 1


def battery_at(states: Iterable[BatteryState], t_end_ns: int) -> BatteryState | None:
    """The last state with ``stamp_ns <= t_end_ns`` (the figure ``papf run`` reports), or None."""
    best = None
    for s in states:
        if s.stamp_ns > t_end_ns:
            break
        best = s
    return best


def remeter_file(path: str | Path, model: str = "motor",
                 params: Mapping[str, object] | None = None,
                 namespace: str | None = None, topics: TopicMap | None = None) -> list[BatteryState]:
    """Every battery state a fresh ``model`` meter gives for the recording's odom + wheels
    (and the robot's measured voltage, as the live meter takes it); a rosbag2 too
    (``topics``: its topic names)."""
    with open_run(path, topics) as rec:
        ns = namespace or rec.run_metadata.get("namespace") or "rosbot"
        remeter = Remeter(model, params)
        for _key, msg, _t in rec.messages([f"{ns}/odom", f"{ns}/wheels",
                                           f"{ns}/battery/measured"]):
            if isinstance(msg, Odometry | WheelStates):
                remeter.feed(msg)
            elif isinstance(msg, BatteryVoltage):
                remeter.measured(msg)
    return remeter.states
