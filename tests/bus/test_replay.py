"""``papf replay`` over a real router: it brings its own router when none is given (as ``papf
run`` does); it refuses a namespace where a live stack runs, whatever the recording's metadata
says, and a lone recorder does not make it refuse (a recorder acts on nothing); ROS-style topic
names are mapped to keys and the impossible ones skipped."""

from __future__ import annotations

import subprocess
import sys
import time

import pytest
import zenoh

from common.transport import zenoh_config
from nodes.recorder.writer import RunWriter
from papf.launch.supervisor import free_port, wait_port
from schemas import Keys, Twist
from tests.support.cli import papf
from tests.support.recordings import write_odom_recording, write_ros_topics, write_synthetic

CMD = [sys.executable, "-m", "papf", "replay"]


def test_replay_without_a_router_serves_its_own(tmp_path):
    import zenoh

    from common.transport import zenoh_config

    rec = tmp_path / "run.mcap"
    write_synthetic(rec, total_k=200)
    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    proc = subprocess.Popen([*CMD, str(rec), "--rate", "0.5", "--listen", endpoint],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            stdin=subprocess.DEVNULL)
    got: list[bytes] = []
    try:
        assert wait_port(port, 60.0, abort=lambda: proc.poll() is not None), proc.stderr.read()
        with zenoh.open(zenoh_config("client", [endpoint])) as s:
            sub = s.declare_subscriber("rosbot/odom", lambda sample: got.append(b""))
            _, err = proc.communicate(timeout=120)
            sub.undeclare()
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, err
    assert f"replaying through its own router on {endpoint}" in err
    assert got   # a client of that router heard the recording


def _replay(rec, router: str) -> subprocess.CompletedProcess:
    return papf("replay", str(rec), "--rate", "0", "--connect", router, timeout=120)


def test_a_lone_recorder_does_not_make_replay_refuse_but_a_planner_does(tmp_path, router,
                                                                       session):
    rec = tmp_path / "run.mcap"
    write_synthetic(rec)
    token = session.liveliness().declare_token("rosbot/alive/recorder")
    try:
        res = _replay(rec, router)
        assert res.returncode == 0, res.stderr
        planner = session.liveliness().declare_token("rosbot/alive/planner")
        try:
            res = _replay(rec, router)
            assert res.returncode == 2 and "alive: planner" in res.stderr
            assert "recorder" not in res.stderr.split("alive:")[1].split(")")[0]
        finally:
            planner.undeclare()
    finally:
        token.undeclare()


def test_the_passive_nodes_come_from_the_declared_ports():
    from papf.cli.replay import passive_nodes

    assert passive_nodes() == {"recorder", "viewer"}


def test_the_replay_guard_is_not_fooled_by_the_metadata(tmp_path, router):
    """Metadata namespace 'elsewhere', keys under 'rosbot' where a planner is alive: refused,
    and not one cmd_vel reaches the live namespace."""
    path = tmp_path / "foreign.mcap"
    with RunWriter(path, {"namespace": "elsewhere"}) as w:
        for i in range(1000):
            w.write_message("rosbot/cmd_vel", Twist(stamp_ns=i, v=0.5, w=0.0))
    got = []
    with zenoh.open(zenoh_config("client", [router])) as s:
        token = s.liveliness().declare_token(Keys("rosbot").alive("base_driver"))
        sub = s.declare_subscriber("rosbot/cmd_vel", lambda sample: got.append(1))
        for extra in ([], ["--namespace", "r2"]):
            p = papf("replay", str(path), "--rate", "0", "--connect", router, *extra, timeout=120)
            assert p.returncode == 2 and "live stack runs in namespace 'rosbot'" in p.stderr, p.stderr
            assert len(p.stderr.strip().splitlines()) == 1
        time.sleep(0.3)
        assert got == []
        sub.undeclare()
        token.undeclare()


@pytest.fixture
def recording(tmp_path):
    return write_odom_recording(tmp_path / "run.mcap")


@pytest.fixture
def ros_recording(tmp_path):
    return write_ros_topics(tmp_path / "ros.mcap")


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
