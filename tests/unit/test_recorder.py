"""Recording core (pure): writer -> reader round trip, schemas, garbage, truncation, recover, CLI."""

from __future__ import annotations

import json
import shutil

import jsonschema
import msgpack
import numpy as np
import pytest
from mcap.reader import make_reader

from common.errors import ConfigError, RecordingError
from common.outfiles import OutputError
from papf.recording import (
    RunWriter,
    iter_messages,
    key_matches,
    open_recording,
    peek_stamp,
    read_metadata,
    recover,
    type_for_key,
)
from schemas import Odometry, Scan, Twist
from schemas.messages import ALL_MESSAGES
from tests.support.recordings import key_of, sample


def write_all_types(path, receive_ns=5):
    with RunWriter(path, {"world": "energy", "seed": 7, "params": {"v_max": 0.5}}) as w:
        for i, msg_type in enumerate(ALL_MESSAGES):
            w.write_message(key_of(msg_type), sample(msg_type, 1000 + i), receive_ns=receive_ns)
        w.add_metadata("result", {"outcome": "reached", "charge_mAh": 1.5})


def test_round_trip_every_message_type(tmp_path):
    path = tmp_path / "all.mcap"
    write_all_types(path)
    got = {key: (msg, t) for key, msg, t in iter_messages(path)}
    for i, msg_type in enumerate(ALL_MESSAGES):
        msg, log_time = got[key_of(msg_type)]
        assert msg == sample(msg_type, 1000 + i)
        assert log_time == 1000 + i  # log time is the message's stamp


def test_stock_mcap_reader_schemas_validate_payloads(tmp_path):
    path = tmp_path / "all.mcap"
    write_all_types(path, receive_ns=42)
    seen = set()
    with open(path, "rb") as f:
        reader = make_reader(f)
        for schema, channel, message in reader.iter_messages():
            assert channel.message_encoding == "msgpack" and schema.encoding == "jsonschema"
            assert channel.topic.startswith("rosbot/")
            wire = msgpack.unpackb(message.data, raw=False)
            assert schema.name == wire["_type"]
            jsonschema.validate(ALL_MESSAGES[0].to_json_compatible(wire), json.loads(schema.data))
            assert message.publish_time == 42
            seen.add(schema.name)
        meta = {m.name: m.metadata for m in reader.iter_metadata()}
    assert seen == {m.TYPE for m in ALL_MESSAGES}
    assert meta["run"]["world"] == "energy" and meta["run"]["seed"] == "7"
    assert json.loads(meta["run"]["params"]) == {"v_max": 0.5}
    assert meta["run"]["software"] == "papf-stack" and meta["run"]["software_version"]
    assert meta["result"] == {"outcome": "reached", "charge_mAh": "1.5"}


def test_garbage_and_unknown_keys_are_recorded_raw(tmp_path):
    path = tmp_path / "g.mcap"
    good = Twist(stamp_ns=9, v=0.1, w=0.0)
    with RunWriter(path, {}) as w:
        w.write("rosbot/cmd_vel", b"\xc1\x00 not msgpack", receive_ns=111)
        w.write("rosbot/cmd_vel", good.to_bytes(), receive_ns=112)
        w.write("rosbot/custom/thing", msgpack.packb({"stamp_ns": 5, "a": 1}), receive_ns=113)
        w.write("elsewhere/blob", b"\xc1\xc1", receive_ns=114)
        w.write("elsewhere/empty", b"", receive_ns=115)
    with open_recording(path) as rec:
        got = list(rec.messages(log_time_order=False))
        channels = {c.topic: c for c in rec.summary.channels.values()}
    assert got[0] == ("rosbot/cmd_vel", b"\xc1\x00 not msgpack", 111)  # nothing stamped yet: receive time
    assert got[1] == ("rosbot/cmd_vel", good, 9)
    assert got[2] == ("rosbot/custom/thing", msgpack.packb({"stamp_ns": 5, "a": 1}), 5)
    # unstamped after stamped ones: logged at the last stamp seen (stays on the sim-time line)
    assert got[3:] == [("elsewhere/blob", b"\xc1\xc1", 5), ("elsewhere/empty", b"", 5)]
    assert channels["rosbot/custom/thing"].schema_id == 0
    assert channels["rosbot/custom/thing"].message_encoding == "msgpack"
    assert channels["elsewhere/blob"].message_encoding == "application/octet-stream"


def test_log_times_may_go_backwards_and_read_back_in_order(tmp_path):
    path = tmp_path / "b.mcap"
    with RunWriter(path, {}) as w:
        for stamp in (300, 100, 200):
            w.write_message("rosbot/odom", Odometry(stamp_ns=stamp, x=0, y=0, yaw=0, v=0, w=0))
        w.write_message("rosbot/cmd_vel", Twist(stamp_ns=150, v=0, w=0))
    assert [t for _, _, t in iter_messages(path)] == [100, 150, 200, 300]
    assert [t for _, _, t in iter_messages(path, log_time_order=False)] == [300, 100, 200, 150]
    assert [k for k, _, _ in iter_messages(path, keys="rosbot/cmd_vel")] == ["rosbot/cmd_vel"]


def test_key_helpers():
    assert key_matches("rosbot/**", "rosbot/planner/state")
    assert key_matches("**", "a") and key_matches("rosbot/*", "rosbot/scan")
    assert not key_matches("rosbot/*", "rosbot/planner/state")
    assert key_matches("*/scan", "r2/scan") and not key_matches("rosbot/scan", "r2/scan")
    assert key_matches("rosbot/**/state", "rosbot/planner/state")
    assert type_for_key("lab/r1/planner/state").TYPE == "papf/PlannerState/v2"
    assert type_for_key("rosbot/sim/pose") is Odometry and type_for_key("scan") is None
    assert type_for_key("rosbot/nothing") is None


def test_peek_stamp_small_large_and_bad():
    scan = sample(Scan, 77)
    big = Scan(**{**{n: getattr(scan, n) for n, _, _ in Scan._FIELDS},
                  "ranges": np.ones(5000, dtype=np.float32)})
    assert peek_stamp(scan.to_bytes()) == 77 and peek_stamp(big.to_bytes()) == 77
    assert peek_stamp(msgpack.packb({"stamp_ns": -1})) is None
    assert peek_stamp(msgpack.packb({"stamp_ns": 1.5})) is None
    assert peek_stamp(msgpack.packb([1, 2])) is None and peek_stamp(b"\xc1" * 300) is None
    assert peek_stamp(b"") is None


def write_one_chunk_per_message(path, n: int) -> list[int]:
    """Write n odometry messages, flushing each into its own chunk; the chunks' end offsets."""
    with RunWriter(path, {"world": "w"}) as w:
        for i in range(n):
            w.write_message("rosbot/odom", Odometry(stamp_ns=i, x=i, y=0, yaw=0, v=0, w=0))
            w.flush()
    with open(path, "rb") as f:
        chunks = make_reader(f).get_summary().chunk_indexes
    assert len(chunks) == n
    return [c.chunk_start_offset + c.chunk_length for c in chunks]


@pytest.mark.parametrize("cut_fraction", [0.0, 0.1, 0.37, 0.5, 0.81, 0.999])
def test_truncated_file_raises_and_recover_keeps_everything_before_the_cut(tmp_path, cut_fraction):
    full = tmp_path / "full.mcap"
    ends = write_one_chunk_per_message(full, 40)
    data = full.read_bytes()
    cut = max(3, int(len(data) * cut_fraction))
    broken = tmp_path / "broken.mcap"
    broken.write_bytes(data[:cut])
    with pytest.raises(RecordingError, match="papf recover"):
        list(iter_messages(broken))
    expected = sum(1 for end in ends if end <= cut)
    if cut < 8:
        with pytest.raises(RecordingError, match="nothing to recover"):
            recover(broken, tmp_path / "fixed.mcap")
        return
    stats = recover(broken, tmp_path / "fixed.mcap")
    assert stats.messages == expected
    got = list(iter_messages(tmp_path / "fixed.mcap"))
    assert [m.message.x for m in got] == [float(i) for i in range(expected)]
    if expected:
        assert read_metadata(tmp_path / "fixed.mcap")["run"]["world"] == "w"
        assert stats.log_span_s == pytest.approx((expected - 1) * 1e-9)


def test_recover_a_complete_file_keeps_all_and_refuses_to_overwrite(tmp_path):
    path = tmp_path / "all.mcap"
    write_all_types(path)
    stats = recover(path, tmp_path / "copy.mcap")
    assert stats.complete and stats.messages == len(ALL_MESSAGES)
    assert list(iter_messages(path)) == list(iter_messages(tmp_path / "copy.mcap"))
    with pytest.raises(RecordingError, match="same file"):
        recover(path, path)
    (tmp_path / "text.mcap").write_text("hello world, not an mcap")
    with pytest.raises(RecordingError, match="MCAP magic"):
        recover(tmp_path / "text.mcap", tmp_path / "x.mcap")
    with pytest.raises(RecordingError, match="not an MCAP"):
        open_recording(tmp_path / "text.mcap")


def test_time_based_flush_makes_messages_survive_a_crash(tmp_path):
    """No close(): what a SIGKILL leaves. Flushed messages are recoverable, later ones not yet."""
    now = [0.0]
    path = tmp_path / "live.mcap"
    w = RunWriter(path, {}, flush_interval_s=0.2, clock=lambda: now[0])
    for i in range(10):
        w.write_message("rosbot/cmd_vel", Twist(stamp_ns=i, v=0, w=0))
    assert recover(path, tmp_path / "a.mcap").messages == 0  # still in the open chunk
    now[0] = 0.25
    w.maybe_flush()  # an idle tick after the interval
    w.write_message("rosbot/cmd_vel", Twist(stamp_ns=10, v=0, w=0))
    assert recover(path, tmp_path / "b.mcap").messages == 10
    now[0] = 0.5
    w.write_message("rosbot/cmd_vel", Twist(stamp_ns=11, v=0, w=0))  # flushes on write too
    assert recover(path, tmp_path / "c.mcap").messages == 12
    w.close()
    shutil.copy(path, tmp_path / "done.mcap")
    assert len(list(iter_messages(tmp_path / "done.mcap"))) == 12


def test_writer_rejects_bad_settings(tmp_path):
    with pytest.raises(RecordingError, match="compression"):
        RunWriter(tmp_path / "x.mcap", {}, compression="gzip")
    with pytest.raises(OutputError, match="does not exist"):
        RunWriter(tmp_path / "no" / "such" / "dir.mcap", {})


def parser():
    from papf.cli import build_parser

    return build_parser()


def cli(*argv: str) -> int:
    args = parser().parse_args(argv)
    return args.func(args)


def test_cli_recover_and_info(tmp_path, capsys):
    full = tmp_path / "run.mcap"
    write_one_chunk_per_message(full, 20)
    broken = tmp_path / "broken.mcap"
    broken.write_bytes(full.read_bytes()[: full.stat().st_size // 2])
    assert cli("info", str(broken)) == 2
    assert "papf recover" in capsys.readouterr().err
    assert cli("recover", str(broken), "--json") == 0
    report = json.loads(capsys.readouterr().out)
    assert report["output"] == str(tmp_path / "broken.recovered.mcap") and report["messages"] > 0
    assert cli("info", report["output"], "--json") == 0
    info = json.loads(capsys.readouterr().out)
    assert info["messages"] == {"rosbot/odom": report["messages"]}
    assert info["metadata"]["run"]["world"] == "w"
    assert cli("recover", str(tmp_path / "missing.mcap")) == 2


def test_cli_options():
    args = ["replay", "x.mcap", "--rate", "0", "--keys", "a/*", "--keys", "b/**"]
    a = parser().parse_args(args)
    assert a.rate == 0 and a.keys == ["a/*", "b/**"] and a.namespace is None  # None: no remap
    assert parser().parse_args([*args, "--namespace", "r2"]).namespace == "r2"
    r = parser().parse_args(["record", "o.mcap", "--meta", "a=b", "--connect", "tcp/h:1"])
    assert r.out == "o.mcap" and r.meta == ["a=b"] and r.namespace == "rosbot"


def test_recorder_meta_arguments():
    from nodes.recorder.__main__ import parse_meta

    assert parse_meta(["world=energy", "expr=a=b", "empty="]) == {
        "world": "energy", "expr": "a=b", "empty": ""}
    with pytest.raises(ConfigError, match="key=value"):
        parse_meta(["novalue"])
