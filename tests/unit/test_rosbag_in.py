"""Bags in: a rosbag2 written by rosbags' own Writer (tests/support/bags.py) read by papf
info / report / animate / replay; figures against what the writer knows."""

from __future__ import annotations

import json
import math

import pytest

from common.errors import ConfigError
from papf.cli import main
from papf.recording.replay import replay
from papf.recording.rosbag import (
    BagRecording,
    TopicMap,
    is_rosbag,
    measured_charge_mAh,
    open_run,
)
from papf.report.metrics import BAG, run_metrics
from schemas.messages import BY_TYPE, BatteryVoltage, Odometry, Scan, Twist, WheelStates
from tests.support.bags import TOPICS, VOLTAGE, write_bag
from tests.support.cli import papf


@pytest.fixture(scope="module")
def bags(tmp_path_factory):
    root = tmp_path_factory.mktemp("bags")
    truth = write_bag(root / "mcap")
    write_bag(root / "sqlite", storage="sqlite3")
    write_bag(root / "nocurrent", with_current=False)
    return root, truth


def close(a: float, b: float, rel: float) -> bool:
    return abs(a - b) <= rel * abs(b)


@pytest.mark.parametrize("name", ["mcap", "sqlite", "mcap/mcap.mcap", "sqlite/sqlite.db3"])
def test_path_duration_and_measured_charge_within_tolerance(bags, name):
    root, truth = bags
    assert is_rosbag(root / name)
    m = run_metrics(root / name)
    assert m.outcome == BAG and m.pose_source == "odom"
    assert close(m.path_length_m, truth.path_length_m, 0.02)
    assert close(m.duration_s, truth.duration_s, 0.05)
    assert close(m.measured_charge_mAh, truth.charge_mAh, 0.02)
    assert m.charge_mAh > 0 and m.energy_model == "motor"     # re-metered from the odometry
    assert m.t_end_s == pytest.approx(truth.span_s)           # the bag's time starts near 0


def test_report_json_per_bag_files_and_null_without_current(bags, capsys):
    root, truth = bags
    out = root / "report"
    assert main(["report", str(root / "mcap"), str(root / "sqlite"), str(root / "nocurrent"),
                 "--json", "--out", str(out)]) == 0
    rows = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert [r["file"] for r in rows] == ["mcap", "nocurrent", "sqlite"]
    for r in rows:   # the fixed fields (DESIGN §10)
        assert close(r["path_length_m"], truth.path_length_m, 0.02)
        assert close(r["duration_s"], truth.duration_s, 0.05)
        assert r["charge_mAh"] == rows[0]["charge_mAh"] > 0   # same drive, re-metered alike
    assert close(rows[0]["measured_charge_mAh"], truth.charge_mAh, 0.02)
    assert close(rows[2]["measured_charge_mAh"], truth.charge_mAh, 0.02)
    assert rows[1]["measured_charge_mAh"] is None              # no current in /battery
    md = (out / "report.md").read_text()
    assert "## Bags recorded on the robot" in md and "none (/battery carries no current)" in md
    assert "no live meter recorded" in md
    for png in ("charge.png", "trajectories-bag_mcap.png", "motion-bag_mcap.png",
                "mind-bag_mcap.png"):
        assert (out / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_other_topic_names_through_the_mapping(tmp_path, capsys):
    names = {"odom": "/odom", "battery": "/battery_state"}
    truth = write_bag(tmp_path / "other", names=names)
    with pytest.raises(ConfigError, match=r"no /battery .* --topics"):   # /odom: found alone
        run_metrics(tmp_path / "other")
    m = run_metrics(tmp_path / "other", topics=TopicMap.parse("odom=/odom, battery=/battery_state"))
    assert close(m.measured_charge_mAh, truth.charge_mAh, 0.02)
    assert close(m.path_length_m, truth.path_length_m, 0.02)
    assert main(["info", str(tmp_path / "other"), "--topics",
                 "odom=/odom,battery=/battery_state"]) == 0
    assert "/battery_state" in capsys.readouterr().out
    # the report too (a fleet's recording is looked for first: a bag is never one)
    assert main(["report", str(tmp_path / "other"), "--out", str(tmp_path / "rep"), "--topics",
                 "odom=/odom,battery=/battery_state"]) == 0


@pytest.mark.parametrize("text", ["odom", "wheels=/x", "odom=/a,odom=/b", "odom=nope",
                                  "scan=/a b"])
def test_bad_mapping_exits_2_with_one_line(bags, capsys, text):
    root, _truth = bags
    assert main(["report", str(root / "mcap"), "--topics", text]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--topics" in err and "Traceback" not in err


def test_missing_topic_is_one_clear_line(tmp_path, capsys):
    write_bag(tmp_path / "noscan", leave_out=("scan", "tf"))
    for cmd in (["report", str(tmp_path / "noscan")], ["info", str(tmp_path / "noscan")],
                ["animate", str(tmp_path / "noscan"), str(tmp_path / "a.gif")]):
        # info still lists what the bag holds (exit 0), the missing role on stderr
        assert main(cmd) == (0 if cmd[0] == "info" else 2)
        out, err = capsys.readouterr()
        err = err.strip()
        assert len(err.splitlines()) == 1
        assert "no /scan (sensor_msgs/msg/LaserScan) in the bag" in err and "/odometry/filtered" in err
        assert cmd[0] != "info" or "/odometry/filtered" in out
    write_bag(tmp_path / "notf", leave_out=("tf",))          # /tf is optional
    assert run_metrics(tmp_path / "notf").measured_charge_mAh is not None


def test_wrong_type_on_a_role_is_named(bags):
    root, _truth = bags
    with pytest.raises(ConfigError, match="/cmd_vel is geometry_msgs/msg/Twist, not nav_msgs"):
        BagRecording(root / "mcap", TopicMap.parse("odom=/cmd_vel"))


def test_info_lists_topics_and_roles(bags, capsys):
    root, _truth = bags
    assert main(["info", str(root / "mcap"), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["rosbag2"] and set(info["topics"]) == {t for t, *_ in TOPICS.values()}
    assert info["topics"]["/odometry/filtered"]["messages"] == 1201
    assert info["as_our_keys"]["rosbot/wheels"] == 1201
    assert main(["info", str(root / "sqlite")]) == 0
    assert "/odometry/filtered" in capsys.readouterr().out


def test_bag_as_our_messages(bags):
    root, _truth = bags
    with open_run(root / "mcap") as rec:
        assert isinstance(rec, BagRecording) and rec.run_metadata["source"] == "rosbag2"
        by_key: dict[str, list] = {}
        for key, msg, log_ns in rec.messages():
            by_key.setdefault(key, []).append(msg)
            assert log_ns == msg.stamp_ns >= 0
    kinds = {k: type(v[0]) for k, v in by_key.items()}
    assert kinds == {"rosbot/odom": Odometry, "rosbot/wheels": WheelStates,
                     "rosbot/battery/measured": BatteryVoltage, "rosbot/cmd_vel": Twist,
                     "rosbot/scan": Scan}
    assert by_key["rosbot/battery/measured"][0].voltage == pytest.approx(VOLTAGE)
    odom = by_key["rosbot/odom"]
    assert odom[0].stamp_ns == 0 and odom[-1].stamp_ns == 24_000_000_000
    moving = odom[600]
    assert (moving.v, moving.w) == (pytest.approx(0.5), pytest.approx(0.25))
    assert [w.stamp_ns for w in by_key["rosbot/wheels"]] == [o.stamp_ns for o in odom]
    assert len(by_key["rosbot/scan"][0].ranges) == 720


def test_replay_publishes_our_messages_on_our_keys(bags):
    root, _truth = bags
    got = []
    stats = replay(root / "sqlite", lambda key, data: got.append((key, data)), rate=0)
    assert stats.messages == len(got) == 1201 * 2 + 241 * 3
    for key, data in got[:50]:
        msg = BY_TYPE[_type_of(data)].from_bytes(data)
        assert key.startswith("rosbot/") and msg.stamp_ns >= 0


def _type_of(data: bytes) -> str:
    import msgpack
    return msgpack.unpackb(data)["_type"]


def test_animate_a_bag(bags, tmp_path):
    root, _truth = bags
    assert main(["animate", str(root / "mcap"), str(tmp_path / "bag.gif"), "--speed", "24",
                 "--fps", "2", "--dpi", "30"]) == 0
    assert (tmp_path / "bag.gif").read_bytes()[:6] in (b"GIF89a", b"GIF87a")


def test_measured_charge_integral():
    s = 1_000_000_000
    samples = [(0, 1.0), (s, 1.0), (2 * s, 3.0), (3 * s, None), (4 * s, 2.0), (5 * s, 2.0)]
    # 1 A s + 2 A s (trapezoid 1..3 A) + gap (None) + 2 A s = 5 A s
    assert measured_charge_mAh(samples, 0, 5 * s) == pytest.approx(5 / 3.6)
    # clipped to [0.5 s, 1.5 s]: 0.5 A s + (1 + 2) / 2 * 0.5 = 1.25 A s
    assert measured_charge_mAh(samples, s // 2, 3 * s // 2) == pytest.approx(1.25 / 3.6)
    assert measured_charge_mAh([(0, None), (s, None)], 0, s) is None
    assert math.isclose(measured_charge_mAh([(0, -1.0), (s, -1.0)], 0, s), -1 / 3.6)


def test_a_bags_mcap_alone_is_still_a_bag(bags, tmp_path):
    root, truth = bags
    import shutil
    shutil.copy(root / "mcap" / "mcap.mcap", tmp_path / "copied.mcap")   # no metadata.yaml
    assert is_rosbag(tmp_path / "copied.mcap")
    assert close(run_metrics(tmp_path / "copied.mcap").measured_charge_mAh, truth.charge_mAh, 0.02)
    # without the odometry topic (under the mapping) it is a plain CDR MCAP
    assert not is_rosbag(tmp_path / "copied.mcap", TopicMap.parse("odom=/elsewhere"))


def test_our_recordings_are_not_bags(tmp_path):
    from nodes.recorder.writer import RunWriter
    from papf.recording.reader import Recording

    with RunWriter(tmp_path / "ours.mcap", {"namespace": "rosbot"}) as w:
        w.write_message("rosbot/odom", Odometry(stamp_ns=0, x=0.0, y=0.0, yaw=0.0, v=0.0, w=0.0))
    assert not is_rosbag(tmp_path / "ours.mcap") and not is_rosbag(tmp_path)
    with open_run(tmp_path / "ours.mcap") as rec:
        assert isinstance(rec, Recording)


def test_a_bag_with_other_names_gets_the_exact_topics_option(tmp_path):
    from tests.support.bags import write_bag

    bag = tmp_path / "bag"
    write_bag(bag, names={"odom": "/wheel_odom"})   # neither the ROSbot's name nor the face's
    res = papf("report", str(bag))
    assert res.returncode == 2 and \
        res.stderr.strip().endswith("Read it with --topics odom=/wheel_odom")
    assert "chars)" not in res.stderr
    res = papf("report", str(bag), "--topics", "odom=/wheel_odom")
    assert res.returncode == 0, res.stderr
    res = papf("info", str(bag))   # info still lists what the bag holds
    assert res.returncode == 0 and "/wheel_odom" in res.stdout and \
        "--topics odom=/wheel_odom" in res.stderr
