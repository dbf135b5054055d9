"""The recorder process closes its file at run_ended and says so."""

from __future__ import annotations

from papf.recording import (
    open_recording,
)
from schemas import Keys, Odometry
from tests.support.recordings import sample


def test_recorder_closes_its_file_at_run_ended_and_says_so(tmp_path):
    import sys
    import time

    import zenoh

    from common.transport import wait_alive, zenoh_config
    from papf.launch.supervisor import Supervisor, free_port, wait_port
    from schemas import Event

    port, out = free_port(), tmp_path / "run.mcap"
    ep = f"tcp/127.0.0.1:{port}"
    closed = []
    with Supervisor(show=lambda *_: False) as sup:
        sup.start("router", [sys.executable, "-m", "papf.launch.router", "--listen", ep])
        assert wait_port(port, 15.0)
        rec = sup.start("recorder", [sys.executable, "-m", "nodes.recorder", "--out", str(out),
                                     "--close-on-run-ended", "--connect", ep, "--namespace", "tack"])
        with zenoh.open(zenoh_config("client", [ep])) as s:
            s.declare_subscriber("tack/events", lambda smp: closed.append(
                Event.from_bytes(smp.payload.to_bytes())))
            # alive: its subscriptions reached the router before its token reached us
            assert not wait_alive(s, Keys("tack"), ["recorder"], 30.0,
                                  abort=lambda: rec.returncode is not None), list(rec.tail)
            deadline = time.monotonic() + 30
            for k in range(200):
                s.put("tack/odom", sample(Odometry, 1_000_000 * (k + 1)).to_bytes())
            s.put("tack/events", Event(stamp_ns=300_000_000, kind="run_ended",
                                       source="launcher").to_bytes())
            while not any(e.kind == "recording_closed" for e in closed) and \
                    time.monotonic() < deadline:
                time.sleep(0.05)
            assert [e.detail for e in closed if e.kind == "recording_closed"] == [str(out)]
            assert rec.returncode is None          # still alive: the launcher stops it
            with open_recording(out) as r:         # complete already, before any stop
                counts = r.counts()
    assert counts == {"tack/odom": 200, "tack/events": 1}
