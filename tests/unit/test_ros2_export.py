"""papf export ros2: every message of every topic read back by rosbags' reader and by the
plain ``mcap`` library with ``mcap-ros2-support``'s decoder (neither is ours)."""

from __future__ import annotations

import json
import math
import os
import time

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore

from nodes.recorder.writer import RunWriter
from papf.cli import main
from papf.recording.ros2_export import export_ros2
from schemas.messages import (
    BatteryState,
    Clock,
    Event,
    Odometry,
    PlannerState,
    Scan,
    Twist,
    WheelStates,
)
from tests.support.messages import planner_debug

STEP = 100_000_000   # [ns] 10 Hz
N = 20
FACE = {"/scan": ("sensor_msgs/msg/LaserScan", N), "/odom": ("nav_msgs/msg/Odometry", N),
        "/tf": ("tf2_msgs/msg/TFMessage", 2 * N),           # odom -> base_link; the wheels
        "/tf_static": ("tf2_msgs/msg/TFMessage", 1),
        "/joint_states": ("sensor_msgs/msg/JointState", N), "/clock": ("rosgraph_msgs/msg/Clock", N),
        "/cmd_vel": ("geometry_msgs/msg/Twist", N),
        "/battery": ("sensor_msgs/msg/BatteryState", N), "/plan": ("nav_msgs/msg/Path", N),
        "/markers": ("visualization_msgs/msg/MarkerArray", N),
        "/robot_description": ("std_msgs/msg/String", 1),
        "/map": ("nav_msgs/msg/OccupancyGrid", 1)}   # the metadata's world, rasterised


def write_run(path, namespaces=("rosbot",)):
    """A short run of ours: the robot drives along x at 0.5 m/s; sim time from 0."""
    with RunWriter(path, {"namespace": namespaces[0], "world": "energy", "planner": "papf"}) as w:
        for k in range(N):
            t = k * STEP
            for i, ns in enumerate(namespaces):
                x, y = 0.05 * k, float(i)
                w.write_message(f"{ns}/scan", Scan(
                    stamp_ns=t, angle_min=-math.pi, angle_increment=2 * math.pi / 8,
                    range_min=0.2, range_max=25.0,
                    ranges=np.array([1, 2, 3, np.inf, 5, 6, 7, 8], np.float32)))
                w.write_message(f"{ns}/odom", Odometry(stamp_ns=t, x=x, y=y, yaw=0.1 * k,
                                                       v=0.5, w=0.0))
                w.write_message(f"{ns}/cmd_vel", Twist(stamp_ns=t, v=0.5, w=-0.1))
                w.write_message(f"{ns}/wheels", WheelStates(stamp_ns=t, speed=(10.0,) * 4,
                                                             torque=(0.1,) * 4))
                w.write_message(f"{ns}/clock", Clock(stamp_ns=t))
                w.write_message(f"{ns}/battery", BatteryState(
                    stamp_ns=t, voltage=11.5, current=1.5, power=17.25, charge_used_mAh=0.04 * k,
                    energy_J=1.7 * k, soc=0.9))
                w.write_message(f"{ns}/planner/state", PlannerState(
                    stamp_ns=t, algorithm="papf", force=(1.0, 0.5), temporary_goal=(x + 1, y),
                    predicted_path=((x, y), (x + 0.5, y), (x + 1.0, y + 0.2)),
                    debug=planner_debug("papf", abandoned_paths=[[(x, y), (x + 0.5, y - 0.5)]],
                                        top_quarks=[(x + 2, y)])))
            w.write_message(f"{namespaces[0]}/events", Event(stamp_ns=t, kind="info",
                                                            source="test"))


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    root = tmp_path_factory.mktemp("export")
    write_run(root / "run.mcap")
    stats = export_ros2(root / "run.mcap", root / "bag")
    return root / "bag", stats


def test_layout_and_counts(exported):
    bag, stats = exported
    assert sorted(os.listdir(bag)) == ["bag.mcap", "metadata.yaml"]
    assert dict(stats.written) == {t: n for t, (_m, n) in FACE.items()}
    assert stats.skipped == N                  # the events are not on the face
    assert not [p for p in os.listdir(bag.parent) if p.startswith(".bag.partial")]


def test_read_back_with_rosbags(exported):
    bag, _stats = exported
    store = get_typestore(Stores.ROS2_JAZZY)
    seen: dict[str, list] = {}
    with AnyReader([bag], default_typestore=store) as reader:
        assert {c.topic: (c.msgtype, c.msgcount) for c in reader.connections} == FACE
        latched = {c.topic for c in reader.connections
                   if any(q.durability.name == "TRANSIENT_LOCAL"
                          for q in c.ext.offered_qos_profiles)}
        assert latched == {"/tf_static", "/robot_description", "/map"}
        for conn, t, data in reader.messages():
            msg = reader.deserialize(data, conn.msgtype)
            seen.setdefault(conn.topic, []).append((t, msg))
    assert {k: len(v) for k, v in seen.items()} == {t: n for t, (_m, n) in FACE.items()}
    # bag time = the wall-clock start of the run + its sim time; header stamps alike
    t0 = seen["/odom"][0][0]
    assert abs(t0 - time.time_ns()) < 600 * 10**9        # real time, not 1970
    assert [t - t0 for t, _m in seen["/odom"]] == [k * STEP for k in range(N)]
    t, odom = seen["/odom"][7]
    assert odom.header.stamp.sec * 10**9 + odom.header.stamp.nanosec == t == t0 + 7 * STEP
    grid = seen["/map"][0][1]
    assert grid.header.frame_id == "map" and grid.info.resolution == pytest.approx(0.05)
    assert (np.asarray(grid.data) == 100).any() and (np.asarray(grid.data) == 0).any()
    assert odom.pose.pose.position.x == pytest.approx(0.35)
    assert (odom.header.frame_id, odom.child_frame_id) == ("odom", "base_link")
    scan = seen["/scan"][3][1]
    assert scan.header.frame_id == "laser" and np.isinf(scan.ranges[3]) and scan.ranges[0] == 1
    assert seen["/cmd_vel"][0][1].angular.z == pytest.approx(-0.1)
    assert seen["/battery"][0][1].current == pytest.approx(-1.5)
    assert len(seen["/plan"][5][1].poses) == 3
    markers = seen["/markers"][5][1].markers
    assert markers[0].action == 3 and {(m.ns, m.id) for m in markers[1:]} == {
        ("mind", 2), ("mind", 3), ("mind/top_quarks", 0), ("mind/abandoned_paths", 0)}
    arrow = next(m for m in markers if (m.ns, m.id) == ("mind", 3))
    assert (arrow.points[0].x, arrow.points[0].y) == (pytest.approx(0.25), 0.0)   # at the robot
    js = seen["/joint_states"][2][1]   # 10 rad/s for 0.2 s: every wheel turned by 2 rad
    assert list(js.name)[0] == "front_left_wheel_joint" and js.position[0] == pytest.approx(2.0)
    assert seen["/clock"][4][1].clock.sec * 10**9 + seen["/clock"][4][1].clock.nanosec == \
        seen["/clock"][4][0]
    (tf_static,) = seen["/tf_static"][0][1].transforms
    assert (tf_static.header.frame_id, tf_static.child_frame_id) == ("base_link", "laser")
    assert "<robot" in seen["/robot_description"][0][1].data


def test_read_back_with_the_mcap_ros2_decoder(exported):
    bag, _stats = exported
    counts: dict[str, int] = {}
    with open(bag / "bag.mcap", "rb") as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        first = None
        for schema, channel, message, decoded in reader.iter_decoded_messages():
            if channel.topic == "/odom" and first is None:
                first = message.log_time
            assert (schema.encoding, channel.message_encoding) == ("ros2msg", "cdr")
            assert schema.name == FACE[channel.topic][0]
            counts[channel.topic] = counts.get(channel.topic, 0) + 1
            if channel.topic == "/odom":
                k = (message.log_time - first) // STEP
                assert decoded.pose.pose.position.x == pytest.approx(0.05 * k)
                assert decoded.twist.twist.linear.x == pytest.approx(0.5)
            elif channel.topic == "/tf":
                assert decoded.transforms[0].child_frame_id in ("base_link", "front_left_wheel_link")
            elif channel.topic == "/markers":
                assert decoded.markers[1].ns == "mind"
    assert counts == {t: n for t, (_m, n) in FACE.items()}


def test_never_overwrites(exported, capsys):
    bag, _stats = exported
    before = (bag / "bag.mcap").stat().st_mtime_ns
    run = bag.parent / "run.mcap"
    assert main(["export", "ros2", str(run), str(bag)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "exists" in err and "never overwrites" in err
    assert (bag / "bag.mcap").stat().st_mtime_ns == before
    assert main(["export", "ros2", str(run), str(run)]) == 2          # IN == OUT
    assert "is the input" in capsys.readouterr().err
    link = bag.parent / "link.mcap"
    os.link(run, link)                                                 # same inode, other name
    assert main(["export", "ros2", str(run), str(link)]) == 2
    assert "is the input" in capsys.readouterr().err


def test_cli_and_several_robots(tmp_path, capsys):
    write_run(tmp_path / "two.mcap", namespaces=("r1", "r2"))
    assert main(["export", "ros2", str(tmp_path / "two.mcap"), str(tmp_path / "out")]) == 0
    assert "/r1/scan" in capsys.readouterr().out
    with AnyReader([tmp_path / "out"]) as reader:
        topics = {c.topic for c in reader.connections}
        shared = {"/map", "/clock"}   # the world frames and the one sim clock
        assert topics == {f"/{ns}{t}" for ns in ("r1", "r2") for t in FACE if t not in shared} | shared
        conns = [c for c in reader.connections if c.topic == "/r2/odom"]
        _c, _t, data = next(iter(reader.messages(connections=conns)))
        odom = reader.deserialize(data, "nav_msgs/msg/Odometry")
    assert (odom.header.frame_id, odom.child_frame_id) == ("odom", "r2/base_link")
    assert odom.pose.pose.position.y == pytest.approx(1.0)


def test_not_a_run_recording(tmp_path, capsys):
    with RunWriter(tmp_path / "empty.mcap", {}) as w:
        w.write_message("x/unrelated", Event(stamp_ns=0, kind="info", source="t"))
    assert main(["export", "ros2", str(tmp_path / "empty.mcap"), str(tmp_path / "o")]) == 2
    assert "no stack topics" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()
    assert not [p for p in os.listdir(tmp_path) if p.startswith(".o.partial")]


def test_our_bag_reads_back_in_report_and_info_without_flags(exported, tmp_path, capsys):
    """papf report and papf info take the export's /odom, /battery, /cmd_vel, /scan as they are."""
    from papf.report.metrics import run_metrics

    bag, _stats = exported
    m = run_metrics(bag)
    assert m.path_length_m == pytest.approx(0.05 * (N - 1), rel=0.02)   # 0.5 m/s for 1.9 s
    assert main(["info", str(bag), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["roles"]["odom"] == "/odom" and info["as_our_keys"]["rosbot/odom"] == N
    assert main(["report", str(bag), "--out", str(tmp_path / "rep")]) == 0
    assert (tmp_path / "rep" / "report.md").is_file()
