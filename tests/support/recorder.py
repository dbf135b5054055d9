"""The recorder node as a process in a test (tests/e2e/test_recorder_process.py, test_replay.py):
started and alive, a condition waited for, what a crash right now would leave."""

from __future__ import annotations

import sys
import time

from common.transport import wait_alive
from papf.recording import recover
from schemas import Keys

ALIVE_TIMEOUT_S = 30.0


def start_recorder(spawn, router, ns, out, session, *extra):
    child = spawn("recorder", [sys.executable, "-m", "nodes.recorder", "--connect", router,
                               "--namespace", ns, "--out", str(out), "--meta", "world=test",
                               *extra])
    assert not wait_alive(session, Keys(ns), ["recorder"], timeout_s=ALIVE_TIMEOUT_S,
                          abort=lambda: child.proc.poll() is not None), "recorder not alive"
    return child


def wait_until(pred, timeout_s: float = 10.0) -> bool:
    deadline = time.monotonic() + timeout_s
    while not pred():
        if time.monotonic() > deadline:
            return False
        time.sleep(0.02)
    return True


def recovered_count(path, tmp_path) -> int:
    """Messages a crash right now would leave (the file is still being written)."""
    return recover(path, tmp_path / "probe.mcap", force=True).messages   # a probe: replaced each time
