"""Settings of every planner and node (common/params.py ``Spec``): any value is refused with one
line or lies in its declared range; no value switches a safety setting off; nodes check their
settings again and refuse bad options at parse time. Property-based (hypothesis)."""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from common.drive import DRIVER_OPTIONS
from common.errors import ConfigError
from common.params import Spec, check_value
from nodes.energy_meter.battery import PackParams
from nodes.energy_meter.core import EnergyMeter
from nodes.energy_meter.models import MOTOR_SPECS, PAPER_SPECS
from nodes.lidar_sim.options import OPTIONS as LIDAR_OPTIONS
from nodes.planner.loop import PlannerLoop
from nodes.planner.registry import PLANNERS, check_setting, make_planner, settings_of
from nodes.planner.settings import NODE as PLANNER_NODE
from nodes.world_sim.core import WorldConfig


def test_nodes_check_their_settings_again():
    with pytest.raises(ConfigError, match="watchdog"):
        WorldConfig.from_rates(watchdog_s=float("inf"))
    with pytest.raises(ConfigError, match="stale_timeout"):
        PlannerLoop(make_planner("apf"), stale_timeout_s=float("nan"))
    with pytest.raises(ConfigError, match="initial_soc"):
        EnergyMeter("motor", {"initial_soc": "2"})


def test_node_options_refused_at_parse_time_with_exit_2():
    for argv in (["nodes.base_driver", "--watchdog", "0"],
                 ["nodes.lidar_sim", "--beams", "nan"],
                 ["nodes.planner", "--stale-timeout", "inf"],
                 ["nodes.planner", "--set", "d_o=nan"]):
        p = subprocess.run([sys.executable, "-m", *argv], capture_output=True, text=True,
                           timeout=60)
        assert p.returncode == 2, (argv, p.stderr)
        assert "must be" in p.stderr


FAST = settings(max_examples=150, deadline=None,
                suppress_health_check=[HealthCheck.too_slow])


text_or_value = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True), st.integers(-10**20, 10**20), st.booleans(),
    st.text(max_size=12), st.sampled_from(["nan", "inf", "-inf", "-1", "0", "1e308", "1e-300",
                                           "true", "0x10", " 0.5 ", "", "gap", "opening"]))


def _assert_in_spec(value, spec: Spec) -> None:
    if spec.kind in (int, float):
        assert type(value) is spec.kind and math.isfinite(value) and spec.contains(value)
    elif spec.kind is str and spec.choices:
        assert value in spec.choices
    else:
        assert type(value) is spec.kind


@FAST
@given(planner=st.sampled_from(sorted(PLANNERS)), data=st.data(), value=text_or_value)
def test_a_planner_setting_is_refused_or_in_its_declared_range(planner, data, value):
    table = settings_of(planner)
    name = data.draw(st.sampled_from(sorted(table)))
    try:
        _, typed = check_setting(planner, name, value)
    except ConfigError as exc:
        assert str(exc).startswith(f"{name}=") and "\n" not in str(exc)
        return
    _assert_in_spec(typed, table[name][1])


ALL_SPECS = {**{f"pack.{k}": v for k, v in PackParams.SPECS.items()},
             **{f"paper.{k}": v for k, v in PAPER_SPECS.items()},
             **{f"motor.{k}": v for k, v in MOTOR_SPECS.items()},
             **{f"driver.{k}": v for k, v in DRIVER_OPTIONS.items()},
             **{f"lidar.{k}": v for k, v in LIDAR_OPTIONS.items()},
             **{f"planner_node.{k}": v for k, v in PLANNER_NODE.items()}}


@FAST
@given(name=st.sampled_from(sorted(ALL_SPECS)), value=text_or_value)
def test_every_node_setting_is_refused_or_in_its_declared_range(name, value):
    spec = ALL_SPECS[name]
    try:
        typed = check_value(name, value, spec)
    except ConfigError:
        return
    _assert_in_spec(typed, spec)


@FAST
@given(value=st.one_of(st.sampled_from([math.nan, math.inf, -math.inf, 0.0, -1.0, "nan", "inf",
                                        "0", "-1", "1e400"]),
                       st.floats(max_value=0.0)))
def test_no_value_switches_a_safety_setting_off(value):
    safety = [(n, s) for n, s in ALL_SPECS.items() if s.safety]
    for planner in PLANNERS:
        safety += [(n, s) for n, (_, s, _) in settings_of(planner).items() if s.safety]
    assert len(safety) >= 10
    for name, spec in safety:
        if spec.lo is not None and spec.lo < 0:   # charges: negative by the paper's law
            continue
        try:
            check_value(name, value, spec)
        except ConfigError:
            continue
        raise AssertionError(f"{name}={value!r} accepted")


def test_numpy_scalars_are_numbers_too():
    assert check_setting("apf", "d_o", np.float64(0.7))[1] == 0.7
