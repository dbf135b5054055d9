"""Record -> replay over a real router (recorder process)."""

from __future__ import annotations

import os
import signal
import threading

import zenoh

from common.transport import zenoh_config
from papf.recording import replay
from schemas import Clock, Odometry
from tests.support.recorder import recovered_count, start_recorder, wait_until

MS = 1_000_000  # [ns]


def test_record_then_replay_over_zenoh(router, spawn, session, tmp_path):
    """Recorder process records what the test publishes; replay under another namespace
    reaches a subscriber byte for byte, in order."""
    out = tmp_path / "rec.mcap"
    child = start_recorder(spawn, router, "live", out, session, "--flush-interval", "0.05")
    sent = []
    for i in range(200):
        sent.append(("odom", Odometry(stamp_ns=i * 5 * MS, x=i, y=1, yaw=0, v=0, w=0).to_bytes()))
        if i % 4 == 0:
            sent.append(("clock", Clock(stamp_ns=i * 5 * MS + 1).to_bytes()))
    for topic, data in sent:
        session.put(f"live/{topic}", data)
    assert wait_until(lambda: recovered_count(out, tmp_path) == len(sent), 20)
    os.killpg(child.proc.pid, signal.SIGTERM)
    assert child.proc.wait(timeout=30) == 0

    got, done = [], threading.Event()

    def on_sample(sample: zenoh.Sample) -> None:
        got.append((str(sample.key_expr), sample.payload.to_bytes()))
        if len(got) == len(sent):
            done.set()

    with zenoh.open(zenoh_config("client", [router])) as sub_session:
        sub = sub_session.declare_subscriber("replayed/**", on_sample)
        probe = session.declare_publisher("replayed/odom")
        assert wait_until(lambda: probe.matching_status.matching), "subscription not seen"
        probe.undeclare()
        stats = replay(out, session, rate=10.0, namespace="replayed")
        assert done.wait(30), f"received {len(got)} of {len(sent)}"
        sub.undeclare()
    assert stats.messages == len(sent)
    assert got == [(f"replayed/{t}", d) for t, d in sent]
