"""The recorder's --format ros2: a rosbag2 written live equals papf export ros2 of the same
samples; its directory is never one a user made; papf run refuses a bad one before starting."""

from __future__ import annotations

import math

import numpy as np
import pytest
from rosbags.highlevel import AnyReader

from common.errors import RecordingError
from nodes.recorder.ros2_bag import Ros2BagWriter, check_bag_dir
from nodes.recorder.writer import RunWriter
from papf.recording.ros2_export import export_ros2
from papf.recording.rosbag import stack_metadata
from schemas.messages import Event, Odometry, Scan, Twist, WheelStates
from tests.support.cli import papf

T0 = 1_700_000_000_000_000_000   # [ns] wall clock of the run's start (receive times)
META = {"namespace": "rosbot", "world": "open", "planner": "papf", "seed": "3"}


def samples():
    for k in range(10):
        t = k * 100_000_000
        yield "rosbot/odom", Odometry(stamp_ns=t, x=0.05 * k, y=0.0, yaw=0.0, v=0.5, w=0.0), T0 + t
        yield "rosbot/scan", Scan(stamp_ns=t, angle_min=-math.pi, angle_increment=math.pi / 4,
                                  range_min=0.2, range_max=25.0,
                                  ranges=np.ones(8, np.float32)), T0 + t + 1000
        yield "rosbot/cmd_vel", Twist(stamp_ns=t, v=0.5, w=0.0), T0 + t + 2000
        yield "rosbot/wheels", WheelStates(stamp_ns=t, speed=(11.8,) * 4, torque=(0.0,) * 4), T0 + t
        yield "rosbot/events", Event(stamp_ns=t, kind="info", source="t"), T0 + t


def read(bag):
    out = {}
    with AnyReader([bag]) as reader:
        for conn, t, data in reader.messages():
            out.setdefault(conn.topic, []).append((t, bytes(data)))
    return out


def test_live_bag_equals_the_export(tmp_path):
    with Ros2BagWriter(tmp_path / "live", META) as w:
        for key, msg, t in samples():
            w.write(key, msg.to_bytes(), t)
        w.write("rosbot/odom", b"\xc1garbage", T0)            # counted and dropped
    assert w.stats.dropped == 10 + 1                           # the events, the garbage
    with RunWriter(tmp_path / "run.mcap", META) as r:
        for key, msg, t in samples():
            r.write(key, msg.to_bytes(), t)
    export_ros2(tmp_path / "run.mcap", tmp_path / "exported")
    live, exported = read(tmp_path / "live"), read(tmp_path / "exported")
    assert live == exported                                    # same topics, times and CDR
    assert live["/odom"][0][0] == T0 and "/map" in live       # real time; the world's map
    meta = stack_metadata(tmp_path / "live")
    assert (meta["world"], meta["planner"], meta["seed"]) == ("open", "papf", "3")


def test_a_bag_directory_is_never_one_a_user_made(tmp_path):
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "notes.txt").write_text("keep")
    with pytest.raises(RecordingError, match="exists"):
        check_bag_dir(tmp_path / "mine")
    with pytest.raises(RecordingError, match="not a rosbag2"):
        check_bag_dir(tmp_path / "mine", force=True)
    with pytest.raises(RecordingError, match="without .mcap"):
        check_bag_dir(tmp_path / "x.mcap")
    with Ros2BagWriter(tmp_path / "bag", META) as w:
        w.write("rosbot/cmd_vel", Twist(stamp_ns=0, v=0.1, w=0.0).to_bytes(), T0)
    with Ros2BagWriter(tmp_path / "bag", META, force=True) as w:   # a bag of ours: replaced
        w.write("rosbot/cmd_vel", Twist(stamp_ns=0, v=0.2, w=0.0).to_bytes(), T0)
    assert (tmp_path / "mine" / "notes.txt").read_text() == "keep"


def test_papf_run_refuses_a_bad_bag_directory_before_starting(tmp_path):
    (tmp_path / "taken").mkdir()
    r = papf("run", "--world", "open", "--planner", "apf", "--record", str(tmp_path / "taken"),
             "--format", "ros2", "--timeout", "5", timeout=120)
    assert r.returncode == 2 and r.stdout == "", r.stderr
    assert len(r.stderr.strip().splitlines()) == 1 and "exists" in r.stderr
