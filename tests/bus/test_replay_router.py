"""Issue #35: ``papf replay`` brings its own router when none is given (as ``papf run``
does), and a lone recorder does not make it refuse (a recorder acts on nothing)."""

from __future__ import annotations

import subprocess
import sys

from papf.launch.supervisor import free_port, wait_port
from tests.support.recordings import write_synthetic

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
    return subprocess.run([*CMD, str(rec), "--rate", "0", "--connect", router],
                          capture_output=True, text=True, timeout=120, stdin=subprocess.DEVNULL)


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
