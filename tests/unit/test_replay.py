"""Replay: timing (fake clock), filters and remapping, progress and bad input."""

from __future__ import annotations

import pytest

from common.errors import RecordingError
from papf.recording import Recording, RunWriter, remap_key, replay
from schemas import Odometry, Twist
from tests.support.cli import papf
from tests.support.recordings import write_ros_topics

MS = 1_000_000  # [ns]


class FakeTime:
    """A clock that only moves when the code under test sleeps."""

    def __init__(self) -> None:
        self.now = 100.0

    def clock(self) -> float:
        return self.now

    def sleep(self, s: float) -> None:
        self.now += s


def write_run(path, ns="rosbot"):
    """Odometry every 20 ms and a cmd_vel every 100 ms over 1 s, plus one event far later."""
    with RunWriter(path, {"namespace": ns}) as w:
        for i in range(50):
            w.write_message(f"{ns}/odom", Odometry(stamp_ns=i * 20 * MS, x=i, y=0, yaw=0, v=0, w=0))
            if i % 5 == 0:
                w.write_message(f"{ns}/cmd_vel", Twist(stamp_ns=i * 20 * MS, v=0.1 * i, w=0))
        w.write(f"{ns}/blob", b"\x01\x02", log_time_ns=10**18)  # a huge gap in log time


def test_replay_paces_by_log_time_and_clamps_gaps(tmp_path):
    path = tmp_path / "run.mcap"
    write_run(path)
    fake, sent = FakeTime(), []
    stats = replay(path, lambda k, d: sent.append((fake.now - 100.0, k, d)), rate=2.0,
                   clock=fake.clock, sleep=fake.sleep, max_gap_s=5.0)
    with Recording(path) as rec:
        expected = [(r.key, r.data, r.log_time_ns) for r in rec.raw()]
    assert [(k, d) for _, k, d in sent] == [(k, d) for k, d, _ in expected]
    for (t, _, _), (_, _, log_ns) in zip(sent[:-1], expected[:-1], strict=True):
        assert t == pytest.approx(log_ns / 1e9 / 2.0, abs=1e-9)  # rate 2: twice as fast
    assert sent[-1][0] == pytest.approx((0.98 + 5.0) / 2.0)  # the huge gap became 5 s
    assert stats.messages == len(expected) and stats.log_span_s == pytest.approx(5.98)


def test_replay_as_fast_as_possible_filters_and_remaps(tmp_path):
    path = tmp_path / "run.mcap"
    write_run(path)
    fake, sent = FakeTime(), []
    stats = replay(path, lambda k, d: sent.append(k), rate=None, keys="rosbot/cmd_vel",
                   namespace="r2", clock=fake.clock, sleep=fake.sleep)
    assert sent == ["r2/cmd_vel"] * 10 and fake.now == 100.0 and stats.per_key == {"r2/cmd_vel": 10}
    assert remap_key("rosbot/planner/state", "rosbot", "lab/r1") == "lab/r1/planner/state"
    assert remap_key("other/scan", "rosbot", "r2") == "other/scan"


def test_replay_stop_progress_and_bad_input(tmp_path):
    path = tmp_path / "run.mcap"
    write_run(path)
    fake, sent, progress = FakeTime(), [], []
    replay(path, lambda k, d: sent.append(k), rate=1.0, clock=fake.clock, sleep=fake.sleep,
           stop=lambda: len(sent) >= 7, progress=lambda done, total: progress.append((done, total)))
    assert len(sent) == 7 and progress[-1] == (7, 61)
    with pytest.raises(RecordingError, match="rate"):
        replay(path, print, rate=-1)
    with pytest.raises(RecordingError, match="publish function"):
        replay(path, object())
    (tmp_path / "cut.mcap").write_bytes(path.read_bytes()[:500])
    with pytest.raises(RecordingError, match="papf recover"):
        replay(tmp_path / "cut.mcap", print)


def test_the_replay_guard_takes_the_namespaces_of_the_keys(tmp_path):
    from nodes.recorder.writer import RunWriter
    from papf.recording.reader import Recording
    from papf.recording.replay import target_namespaces
    from schemas import Twist

    path = tmp_path / "r.mcap"
    with RunWriter(path, {"namespace": "elsewhere"}) as w:
        w.write_message("rosbot/cmd_vel", Twist(stamp_ns=1, v=0.1, w=0.0))
        w.write_message("lab/r1/scan", Twist(stamp_ns=2, v=0.0, w=0.0))
    with Recording(path) as rec:
        assert target_namespaces(rec) == {"rosbot", "lab/r1"}
        assert target_namespaces(rec, namespace="elsewhere") == {"rosbot", "lab/r1"}
        assert target_namespaces(rec, namespace="x") == {"rosbot", "lab/r1"}


@pytest.fixture
def ros_recording(tmp_path):
    return write_ros_topics(tmp_path / "ros.mcap")


def test_replay_bad_rate_and_no_router_are_one_line(ros_recording):
    for args in (("--rate", "nan"), ("--rate", "inf"), ("--rate", "-1"),
                 ("--connect", "tcp/127.0.0.1:1")):
        p = papf("replay", ros_recording, *args)
        assert p.returncode == 2 and len(p.stderr.strip().splitlines()) == 1, (args, p.stderr)
