"""A real recorded run: stock MCAP reader + schema validation, and a --rate 10 replay
into a fresh energy-meter process reproducing the live meter's charge."""

import json

import jsonschema
import msgpack
import pytest
from mcap.reader import make_reader

from papf.recording.replay import replay
from tests.support.e2e import metered_bus, papf_run


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    path = tmp_path_factory.mktemp("rec") / "run.mcap"
    code, res, err = papf_run("--world", "energy", "--planner", "apf", "--seed", "2",
                              "--timeout", "12", "--record", str(path))
    assert res is not None and res["outcome"] == "timeout", err[-3000:]
    return path, res


def test_stock_reader_opens_it_and_every_message_validates_against_its_schema(recorded):
    path, _ = recorded
    seen, validators = {}, {}
    with open(path, "rb") as f:
        reader = make_reader(f)
        for schema, channel, message in reader.iter_messages():
            assert channel.message_encoding == "msgpack"
            assert schema.encoding == "jsonschema" and schema.name.startswith("papf/")
            wire = msgpack.unpackb(message.data, raw=False)
            doc = {k: (v.decode("latin-1") if isinstance(v, bytes) else v) for k, v in wire.items()}
            if schema.id not in validators:   # the schema checked once, not once per message
                doc_schema = json.loads(schema.data)
                cls = jsonschema.validators.validator_for(doc_schema)
                cls.check_schema(doc_schema)
                validators[schema.id] = cls(doc_schema)
            validators[schema.id].validate(doc)
            assert message.log_time == wire["stamp_ns"]
            seen[channel.topic] = seen.get(channel.topic, 0) + 1
    assert {"rosbot/scan", "rosbot/odom", "rosbot/wheels", "rosbot/battery", "rosbot/cmd_vel",
            "rosbot/planner/state", "rosbot/sim/pose", "rosbot/clock"} <= set(seen)
    assert seen["rosbot/scan"] >= 120  # 12 s at 10 Hz


def test_replay_at_rate_10_into_a_fresh_meter_gives_the_live_charge(recorded, spawn):
    path, res = recorded
    ns = "replayed"
    with metered_bus(spawn, ns) as (s, got):
        stats = replay(path, s, rate=10.0, keys=["rosbot/odom", "rosbot/wheels"], namespace=ns)
        assert stats.messages > 1000
        got.wait_for(12_000_000_000)
    live = res["charge_mAh"]  # the live meter's charge at t_end = 12 s
    replayed = max((b for b in got.items if b.stamp_ns <= 12_000_000_000),
                   key=lambda b: b.stamp_ns)
    assert replayed.stamp_ns == 12_000_000_000
    assert replayed.charge_used_mAh == pytest.approx(live, rel=1e-3)
