"""The recorder node as a real process behind a real router: SIGKILL and SIGTERM."""

from __future__ import annotations

import os
import signal
import time

import msgpack

from papf.recording import Recording, recover
from schemas import Keys, Twist
from schemas.messages import ALL_MESSAGES
from tests.support.recorder import recovered_count, start_recorder, wait_until
from tests.support.recordings import key_of, sample


def test_sigkill_loses_at_most_the_last_second(router, spawn, session, tmp_path):
    keys, out = Keys("kill"), tmp_path / "killed.mcap"
    child = start_recorder(spawn, router, keys.ns, out, session)
    pub = session.declare_publisher(keys.cmd_vel)
    rate, duration = 2000, 3.0  # [msgs/s], [s]: under one chunk, so only timed flushes save it
    payloads = [Twist(stamp_ns=i, v=0.1, w=0.0).to_bytes() for i in range(int(rate * duration))]
    sent_at: list[float] = []
    start = time.monotonic()
    while len(sent_at) < len(payloads):
        now = time.monotonic()
        due = min(len(payloads), int((now - start) * rate) + 1)
        while len(sent_at) < due:
            pub.put(payloads[len(sent_at)])
            sent_at.append(now)
        time.sleep(0.001)
    killed_at = time.monotonic()
    os.killpg(child.proc.pid, signal.SIGKILL)
    child.proc.wait(timeout=10)

    stats = recover(out, tmp_path / "fixed.mcap")
    with Recording(tmp_path / "fixed.mcap") as rec:
        got = {m.log_time_ns for m in rec.raw()}
        assert rec.run_metadata["world"] == "test" and rec.run_metadata["namespace"] == "kill"
    must_have = [i for i, t in enumerate(sent_at) if t < killed_at - 1.0]
    missing = [i for i in must_have if i not in got]
    assert not missing, f"{len(missing)} of {len(must_have)} messages lost, first {missing[:5]}"
    assert got <= set(range(len(payloads))) and stats.messages == len(got)


def test_sigterm_closes_a_complete_file_with_every_message(router, spawn, session, tmp_path):
    keys, out = Keys("term"), tmp_path / "run.mcap"
    child = start_recorder(spawn, router, keys.ns, out, session, "--flush-interval", "0.05")
    sent = []
    for i in range(300):
        msg_type = ALL_MESSAGES[i % len(ALL_MESSAGES)]
        key = f"{keys.ns}/{key_of(msg_type).split('/', 1)[1]}"
        sent.append((key, sample(msg_type, 10 * i).to_bytes()))
        if i % 50 == 0:  # bad payloads are recorded too, never crash the recorder
            sent.append((keys.cmd_vel, b"\xc1 garbage"))
            sent.append((keys.key("custom/thing"), msgpack.packb({"anything": i})))
    for key, data in sent:
        session.put(key, data)
    assert wait_until(lambda: recovered_count(out, tmp_path) == len(sent), 20)
    os.killpg(child.proc.pid, signal.SIGTERM)
    assert child.proc.wait(timeout=30) == 0

    with Recording(out) as rec:  # complete: opens without recover
        got = [(m.key, m.data) for m in rec.raw(log_time_order=False)]
        assert sum(rec.counts().values()) == len(sent)
    assert got == sent
