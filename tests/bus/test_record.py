"""``papf record`` by hand over a real router: it says what it records (the namespace's nodes
alive, or that it waits for the stack, and when the first messages came: no silent wait), and
``--duration S`` stops it by itself with a complete file (a bad value is one line before the bus)."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time

from papf.recording.reader import open_recording
from schemas import Clock, Keys
from tests.support import warm
from tests.support.cli import papf, stderr_until


def _until(proc: subprocess.Popen, needle: str, seen: list[str]) -> str:
    return stderr_until(proc, re.escape(needle), seen)


def test_record_before_the_stack_waits_aloud_then_says_when_messages_come(router, session,
                                                                          tmp_path):
    proc = warm.popen([sys.executable, "-m", "papf", "record", str(tmp_path / "r.mcap"),
                       "--connect", router, "--namespace", "t6rec"], stdout=subprocess.DEVNULL,
                      stderr=subprocess.PIPE)
    seen: list[str] = []
    try:
        line = _until(proc, "no node alive yet", seen)
        assert "namespace 't6rec'" in line and "waiting for the stack" in line
        _until(proc, "no --meta world=W", seen)
        pub = session.declare_publisher(Keys("t6rec").clock)
        for k in range(50):            # the stack starts: its clock
            pub.put(Clock(stamp_ns=k * 10_000_000).to_bytes())
            time.sleep(0.02)
        _until(proc, "first messages after", seen)
    finally:
        os.killpg(proc.pid, signal.SIGINT)
        _, err = proc.communicate(timeout=30)
    assert proc.returncode == 0 and "Traceback" not in err, err


def test_record_stops_after_its_duration_with_a_complete_file(router, tmp_path):
    out = tmp_path / "r.mcap"
    res = papf("record", str(out), "--duration", "1", "--connect", router, timeout=60)
    assert res.returncode == 0, res.stderr[-2000:]
    with open_recording(out) as rec:   # the footer is there: it reads back
        assert rec.run_metadata.get("namespace") == "rosbot"


def test_a_bad_duration_is_one_line():
    res = papf("record", "x.mcap", "--duration", "nan", timeout=60)
    assert res.returncode == 2 and len(res.stderr.strip().splitlines()) == 1, res.stderr
    assert "--duration" in res.stderr
