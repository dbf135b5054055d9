"""Schemas: round trips, bad bytes -> SchemaError, JSON Schema validates real messages."""

import math

import jsonschema
import msgpack
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import schemas as s
from common.errors import SchemaError
from schemas.base import Message
from schemas.keys import Keys
from schemas.messages import ALL_MESSAGES

SETTINGS = settings(max_examples=60, deadline=None)
FAST = settings(max_examples=150, deadline=None,
                suppress_health_check=[HealthCheck.too_slow])
# msgpack-able values, including the awkward ones: huge ints, nan/inf, bytes, nesting
scalars = st.one_of(st.none(), st.booleans(), st.integers(-2**63, 2**64 - 1),
                    st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=20),
                    st.binary(max_size=64))
values = st.recursive(scalars, lambda inner: st.one_of(
    st.lists(inner, max_size=6), st.dictionaries(st.text(max_size=8), inner, max_size=6)),
    max_leaves=20)


def samples() -> list[Message]:
    return [
        s.Scan(stamp_ns=100, angle_min=-math.pi, angle_increment=2 * math.pi / 4, range_min=0.2,
               range_max=25.0, ranges=np.array([1.0, np.inf, np.nan, 0.5]), sensor_x=0.02),
        s.Odometry(stamp_ns=1, x=1.0, y=-2.0, yaw=0.5, v=0.2, w=-0.1),
        s.Twist(stamp_ns=2, v=0.3, w=0.1),
        s.WheelStates(stamp_ns=3, speed=(1, 2, 3, 4), torque=(0.1, 0.2, 0.3, 0.4)),
        s.BatteryState(stamp_ns=4, voltage=11.9, current=1.2, power=14.3, charge_used_mAh=1.5,
                       energy_J=60.0, soc=0.99, model="paper"),
        s.BatteryVoltage(stamp_ns=4, voltage=11.7),
        s.Goal(stamp_ns=5, x=10.0, y=0.0, tolerance=0.1),
        s.PlannerState(stamp_ns=6, algorithm="papf", force=(1.0, 2.0), temporary_goal=(1.0, 1.0),
                       predicted_path=((0, 0), (0.03, 0.0)), debug=(
                           s.DebugValue(name="abandoned_paths", kind="paths", unit="m",
                                        paths=(((0, 0), (1, 1)),), dashed=True),
                           s.DebugValue(name="top_quarks", kind="points", unit="m",
                                        points=((2.0, 2.0),), colour=(1.0, 0.0, 0.0, 0.9)),
                           s.DebugValue(name="lane_goal_y", kind="scalar", value=float("nan")),
                           s.DebugValue(name="local_minimum_count", kind="count", value=-2.0))),
        s.PlannerStatus(stamp_ns=7, state="driving", reason="", distance_to_goal=3.0),
        s.Clock(stamp_ns=8),
        s.Event(stamp_ns=9, kind="collision", source="base_driver", x=1.0, y=2.0),
        s.Objects(stamp_ns=10, source="tracker", tracks=(
            s.ObjectTrack(id=3, x=1.0, y=0.5, yaw=0.1, vx=0.3, vy=0.0, length=0.5, width=0.3),
            s.ObjectTrack(id=7, x=-2.0, y=0.0))),
        s.Bodies(stamp_ns=11, robots=("r2",), robot_x=(1.0,), robot_y=(2.0,), robot_yaw=(0.5,),
                 person_x=(3.0,), person_y=(4.0,), person_radius=(0.3,)),
        s.People(stamp_ns=12, x=(1.0, 2.0), y=(0.0, 1.0), vx=(0.5, 0.0), vy=(0.0, -0.5),
                 radius=(0.3, 0.25)),
        s.Twist(stamp_ns=3, v=0.2, w=0.0, plan=(0.0, 0.0, 0.0, 0.02, 0.0, 0.0),
                plan_dt_ns=100_000_000),
        s.LinkHealth(stamp_ns=13, side="robot", rtt_p50_ms=420.0, rtt_p99_ms=690.5, commands=20,
                     obeyed=18, late=2, outages=1, outage_s=2.5, longest_outage_s=2.5),
    ]


@pytest.mark.parametrize("msg", samples(), ids=lambda m: m.TYPE)
def test_round_trip(msg):
    back = type(msg).from_bytes(msg.to_bytes())
    assert back == msg
    assert back.to_bytes() == msg.to_bytes()


@pytest.mark.parametrize("msg", samples(), ids=lambda m: m.TYPE)
def test_bytes_are_those_of_the_wire_map(msg):
    """to_bytes packs tuples where to_wire has lists: the same msgpack bytes."""
    assert msg.to_bytes() == msgpack.packb(msg.to_wire(), use_bin_type=True)


@pytest.mark.parametrize("msg", samples(), ids=lambda m: m.TYPE)
def test_from_normal_builds_the_same_message(msg):
    values = {name: getattr(msg, name) for name, _k, _m in msg._FIELDS}
    fast = type(msg).from_normal(**values)
    assert fast == msg and fast.to_bytes() == msg.to_bytes()
    required = {name: values[name] for name in type(msg)._REQUIRED}
    assert type(msg).from_normal(**required) == type(msg)(**required)


def test_from_normal_names_unknown_and_missing_fields():
    with pytest.raises(TypeError, match="speed"):
        s.Twist.from_normal(stamp_ns=1, speed=2.0)
    with pytest.raises(TypeError, match="stamp_ns"):
        s.Twist.from_normal(v=1.0)


@pytest.mark.parametrize("msg", samples(), ids=lambda m: m.TYPE)
def test_decoding_without_init_equals_the_constructor(msg):
    """from_wire fills a checked instance without __init__: the same fields, values and
    types as building it with the constructor (and so __post_init__'s normal form)."""
    back = type(msg).from_bytes(msg.to_bytes())
    built = type(msg)(**{name: getattr(back, name) for name, _, _ in back._FIELDS})
    assert list(vars(back)) == list(vars(built))
    for name in vars(built):
        a, b = getattr(back, name), getattr(built, name)
        assert type(a) is type(b), name
        if isinstance(a, np.ndarray):
            assert a.dtype == b.dtype and a.tobytes() == b.tobytes()
        else:
            assert repr(a) == repr(b), name


def test_fast_checks_still_refuse_what_the_full_checks_refuse():
    wire = s.Odometry(stamp_ns=1, x=1.0, y=2.0, yaw=0.0, v=0.0, w=0.0).to_wire()
    for field, value in (("x", math.inf), ("y", math.nan), ("stamp_ns", True), ("v", "1"),
                         ("stamp_ns", 1.0)):
        with pytest.raises(SchemaError):
            s.Odometry.from_wire({**wire, field: value})
    assert s.Odometry.from_wire({**wire, "x": 3}).x == 3.0     # an int where a float goes
    assert type(s.Odometry.from_wire({**wire, "x": 3}).x) is float
    wheels = s.WheelStates(stamp_ns=1, speed=(1.0, 2.0), torque=(0.0, 0.0)).to_wire()
    with pytest.raises(SchemaError):
        s.WheelStates.from_wire({**wheels, "speed": [1.0, math.inf]})
    assert s.WheelStates.from_wire({**wheels, "speed": [1, 2.0]}).speed == (1.0, 2.0)


def test_a_twist_recorded_before_plans_decodes_as_a_plain_command():
    wire = msgpack.packb({"_type": s.Twist.TYPE, "stamp_ns": 5, "v": 0.1, "w": 0.2})
    cmd = s.Twist.from_bytes(wire)
    assert (cmd.plan, cmd.plan_dt_ns) == ((), 0)


def test_every_message_type_is_sampled():
    assert {type(m) for m in samples()} == set(s.ALL_MESSAGES)


@pytest.mark.parametrize("msg", samples(), ids=lambda m: m.TYPE)
def test_json_schema_validates_decoded_message(msg):
    wire = msgpack.unpackb(msg.to_bytes(), raw=False)
    jsonschema.validate(type(msg).to_json_compatible(wire), type(msg).json_schema())


def test_json_schema_rejects_wrong_type_tag():
    wire = s.Twist(stamp_ns=1, v=0, w=0).to_wire()
    wire["_type"] = "papf/Scan/v1"
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate(wire, s.Twist.json_schema())


def test_scan_ranges_travel_as_float32_bytes():
    scan = samples()[0]
    wire = msgpack.unpackb(scan.to_bytes(), raw=False)
    assert isinstance(wire["ranges"], bytes) and len(wire["ranges"]) == 16
    assert np.frombuffer(wire["ranges"], "<f4")[0] == 1.0


@pytest.mark.parametrize("payload, match", [
    (b"", "not msgpack"),
    (b"\xc1\xc1garbage", "not msgpack"),
    (msgpack.packb([1, 2, 3]), "expected a map"),
    (msgpack.packb({"_type": "papf/Twist/v2", "stamp_ns": 1, "v": 0.0, "w": 0.0}), "wrong message type"),
    (msgpack.packb({"_type": "papf/Twist/v1", "stamp_ns": 1, "v": 0.0}), "missing field 'w'"),
    (msgpack.packb({"_type": "papf/Twist/v1", "stamp_ns": "x", "v": 0.0, "w": 0.0}), "stamp_ns"),
    (msgpack.packb({"_type": "papf/Twist/v1", "stamp_ns": 1, "v": float("nan"), "w": 0.0}), "finite"),
    (msgpack.packb({"_type": "papf/Twist/v1", "stamp_ns": 1, "v": float("inf"), "w": 0.0}), "finite"),
    (msgpack.packb({"_type": "papf/Twist/v1", "stamp_ns": 1, "v": True, "w": 0.0}), "number"),
])
def test_bad_twist_bytes_raise_schema_error(payload, match):
    with pytest.raises(s.SchemaError, match=match) as info:
        s.Twist.from_bytes(payload)
    assert "papf/Twist/v1" in str(info.value)


def test_bad_arrays_raise_schema_error():
    wire = samples()[0].to_wire()
    with pytest.raises(s.SchemaError, match="float32"):
        s.Scan.from_wire({**wire, "ranges": b"abc"})
    wheels = s.WheelStates(stamp_ns=1, speed=(1, 2, 3, 4), torque=(0, 0, 0, 0)).to_wire()
    with pytest.raises(s.SchemaError, match="number"):
        s.WheelStates.from_wire({**wheels, "speed": [1, "a"]})
    state = samples()[7].to_wire()
    with pytest.raises(s.SchemaError, match=r"\[x, y\] pair"):
        s.PlannerState.from_wire({**state, "predicted_path": [[1, 2, 3]]})
    with pytest.raises(s.SchemaError, match="2 values"):
        s.PlannerState.from_wire({**state, "force": [1.0]})


def test_enumerated_strings_are_checked():
    with pytest.raises(s.SchemaError, match="not one of"):
        s.PlannerStatus.from_wire({**samples()[8].to_wire(), "state": "flying"})


def test_keys_and_namespace():
    k = s.Keys("lab/r1")
    assert k.cmd_vel == "lab/r1/cmd_vel" and k.alive("planner") == "lab/r1/alive/planner"
    assert k.type_of("lab/r1/sim/pose") is s.Odometry
    assert k.type_of("other/scan") is None
    for bad in ("", "/x", "x/", "a/*"):
        with pytest.raises(ValueError):
            s.Keys(bad)


def test_objects_nest_tracks_and_name_a_bad_one():
    msg = s.Objects(stamp_ns=1, source="truth", tracks=[s.ObjectTrack(id=1, x=1.0, y=2.0, vx=0.5)])
    assert msg.tracks == (s.ObjectTrack(id=1, x=1.0, y=2.0, vx=0.5),)
    assert msg.to_dict()["tracks"][0]["vx"] == 0.5
    wire = msg.to_wire()
    wire["tracks"][0]["x"] = "far"
    with pytest.raises(s.SchemaError, match=r"papf/Objects/v1.tracks: papf/ObjectTrack/v1.x"):
        s.Objects.from_wire(wire)
    schema = s.Objects.json_schema()["properties"]["tracks"]
    assert schema["items"]["title"] == "papf/ObjectTrack/v1"


@SETTINGS
@given(st.text(min_size=1, max_size=300))
def test_a_namespace_taken_is_a_plain_printable_key(ns):
    from schemas import Keys

    try:
        Keys(ns)
    except ValueError:
        return
    assert ns.isprintable() and len(ns) <= 200 and "//" not in ns and not set(ns) & set("*$?# ")


def test_namespaces_must_make_valid_keys():
    for bad in ("", "*", "a//b", "/a", "a/", "a$b", "a?b", "a#b", "a b"):
        with pytest.raises(ValueError):
            Keys(bad)
    assert Keys("lab/r1").scan == "lab/r1/scan"


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
