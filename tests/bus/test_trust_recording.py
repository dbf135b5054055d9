"""Issue "trust no input", items 11 and 12: replay of foreign topic names and into the
namespace of a live stack, over a real router."""

from __future__ import annotations

import subprocess
import sys

import pytest
import zenoh
from mcap.writer import Writer

from common.transport import zenoh_config
from papf.recording import RunWriter
from schemas import Keys, Odometry

N = 600


def _odom(i):
    return Odometry(stamp_ns=i * 20_000_000, x=i * 0.01, y=0.0, yaw=0.0, v=0.1, w=0.0)


@pytest.fixture
def recording(tmp_path):
    path = tmp_path / "run.mcap"
    with RunWriter(path, {"world": "open"}, chunk_size=2048) as w:
        for i in range(N):
            w.write_message("rosbot/odom", _odom(i), receive_ns=i)
    return path


def papf(*args, timeout=60):
    return subprocess.run([sys.executable, "-m", "papf", *map(str, args)], capture_output=True,
                          text=True, timeout=timeout, stdin=subprocess.DEVNULL)


# -- replay ----------------------------------------------------------------------------------
@pytest.fixture
def ros_recording(tmp_path):
    path = tmp_path / "ros.mcap"
    with open(path, "wb") as f:
        w = Writer(f)
        w.start()
        s = w.register_schema("std_msgs/String", "ros2msg", b"string data")
        for topic in ("/some/topic", "/bad//topic"):
            c = w.register_channel(topic, "cdr", s)
            for i in range(3):
                w.add_message(c, log_time=i, publish_time=i, data=b"\x00\x01\x00\x00abc")
        w.finish()
    return path


def test_replay_of_ros_style_topics_maps_them_and_skips_the_impossible(ros_recording, router,
                                                                      session):
    got = []
    sub = session.declare_subscriber("some/**", lambda s: got.append(str(s.key_expr)))
    p = papf("replay", ros_recording, "--rate", "0", "--connect", router)
    sub.undeclare()
    assert p.returncode == 0, p.stderr
    assert f"into the Zenoh router at {router}" in p.stderr
    assert "skipped 3 messages" in p.stderr and "/bad//topic" in p.stderr
    assert got == ["some/topic"] * 3


def test_replay_refuses_a_namespace_where_a_live_stack_runs(recording, router):
    with zenoh.open(zenoh_config("client", [router])) as s:
        token = s.liveliness().declare_token(Keys("rosbot").alive("planner"))
        p = papf("replay", recording, "--rate", "0", "--connect", router)
        assert p.returncode == 2 and "live stack runs in namespace 'rosbot'" in p.stderr
        assert "alive: planner" in p.stderr
        p = papf("replay", recording, "--rate", "0", "--connect", router, "--namespace", "r2")
        assert p.returncode == 0, p.stderr
        p = papf("replay", recording, "--rate", "0", "--connect", router, "--into-live")
        assert p.returncode == 0, p.stderr
        token.undeclare()
