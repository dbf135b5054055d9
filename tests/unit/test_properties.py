"""Property-based tests (hypothesis): hostile bytes and hostile settings.

- every schema's decoding: any bytes, and any msgpack map that looks like the message,
  give a message or a counted drop — never another exception;
- stamps: a message is acted on only when its stamp is in ``[0, MAX_STAMP_NS]``;
- parameter validation: any value for any setting of any planner, energy model or node
  option is either refused with a ConfigError or lies in its declared range.
"""

from __future__ import annotations

import logging
import math

import msgpack
import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from common.drive import DRIVER_OPTIONS
from common.errors import ConfigError, SchemaError
from common.params import Spec, check_value
from common.transport import Node
from common.units import MAX_STAMP_NS
from nodes.energy_meter.battery import PackParams
from nodes.energy_meter.models import MOTOR_SPECS, PAPER_SPECS
from nodes.lidar_sim.options import OPTIONS as LIDAR_OPTIONS
from nodes.planner.registry import PLANNERS, check_setting, settings_of
from nodes.planner.settings import NODE as PLANNER_NODE
from schemas import Keys
from schemas.keys import TOPICS
from schemas.messages import ALL_MESSAGES, Odometry

FAST = settings(max_examples=150, deadline=None,
                suppress_health_check=[HealthCheck.too_slow])

# msgpack-able values, including the awkward ones: huge ints, nan/inf, bytes, nesting
scalars = st.one_of(st.none(), st.booleans(), st.integers(-2**63, 2**64 - 1),
                    st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=20),
                    st.binary(max_size=64))
values = st.recursive(scalars, lambda inner: st.one_of(
    st.lists(inner, max_size=6), st.dictionaries(st.text(max_size=8), inner, max_size=6)),
    max_leaves=20)


def _node() -> Node:
    return Node("probe", None, Keys("t"), logging.getLogger("probe"))


@FAST
@given(msg_type=st.sampled_from(ALL_MESSAGES), data=st.binary(max_size=512))
def test_any_bytes_decode_to_a_message_or_a_schema_error(msg_type, data):
    try:
        msg = msg_type.from_bytes(data)
    except SchemaError:
        return
    assert isinstance(msg, msg_type)


@FAST
@given(msg_type=st.sampled_from(ALL_MESSAGES), fields=st.dictionaries(st.text(max_size=12), values,
                                                                       max_size=8),
       overrides=st.data())
def test_any_map_of_the_right_type_decodes_or_is_refused(msg_type, fields, overrides):
    # start from the message's own field names so that deep validation is reached
    wire = {name: overrides.draw(values) for name, _, _ in msg_type._FIELDS}
    wire.update(fields)
    wire["_type"] = msg_type.TYPE
    data = msgpack.packb(wire, use_bin_type=True)
    try:
        msg = msg_type.from_bytes(data)
    except SchemaError:
        return
    assert msg == msg_type.from_bytes(msg.to_bytes())   # a decoded message round-trips


@FAST
@given(topic=st.sampled_from(sorted(TOPICS)), data=st.binary(max_size=256))
def test_node_turns_any_payload_into_a_message_or_a_counted_drop(topic, data):
    node = _node()
    msg = node.accept(topic, data)
    if msg is None:
        assert node.bad_messages[topic] == 1
    else:
        assert isinstance(msg, TOPICS[topic]) and not node.bad_messages


@FAST
@given(stamp=st.integers(-2**63, 2**64 - 1))
def test_a_message_is_acted_on_only_with_a_stamp_in_range(stamp):
    node = _node()
    payload = msgpack.packb({"_type": Odometry.TYPE, "stamp_ns": stamp, "x": 0.0, "y": 0.0,
                             "yaw": 0.0, "v": 0.0, "w": 0.0})
    msg = node.accept("odom", payload)
    assert (msg is not None) == (0 <= stamp <= MAX_STAMP_NS)
    assert node.bad_messages["odom"] == (msg is None)


# -- settings ------------------------------------------------------------------------------------
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
