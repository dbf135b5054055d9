"""``papf record F.mcap --duration S`` stops by itself after S seconds with a complete file
(as the topic tools' --duration does); a bad value is refused in one line before the bus."""

from __future__ import annotations

import subprocess
import sys

from papf.recording.reader import open_recording


def test_record_stops_after_its_duration_with_a_complete_file(router, tmp_path):
    out = tmp_path / "r.mcap"
    res = subprocess.run([sys.executable, "-m", "papf", "record", str(out), "--duration", "1",
                          "--connect", router], capture_output=True, text=True, timeout=60)
    assert res.returncode == 0, res.stderr[-2000:]
    with open_recording(out) as rec:   # the footer is there: it reads back
        assert rec.run_metadata.get("namespace") == "rosbot"


def test_a_bad_duration_is_one_line():
    res = subprocess.run([sys.executable, "-m", "papf", "record", "x.mcap", "--duration", "nan"],
                         capture_output=True, text=True, timeout=60)
    assert res.returncode == 2 and len(res.stderr.strip().splitlines()) == 1, res.stderr
    assert "--duration" in res.stderr
