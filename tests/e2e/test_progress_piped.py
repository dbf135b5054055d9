"""Every command that can take more than a few seconds says how far it is, piped too.

Each command runs with its output piped (not a terminal), and its progress lines must come
while it is still working: the long studies are stopped after their first progress line
(they take minutes); ``papf animate`` runs to the end and its progress lines must come
before its last line.
"""

from __future__ import annotations

import subprocess
import sys

import pytest

from papf.launch.supervisor import free_port
from tests.support import warm
from tests.support.cli import interrupt, stderr_until
from tests.support.recordings import write_drive

pytestmark = pytest.mark.e2e


def _first_progress(argv: list[str], pattern: str, cwd, timeout_s: float = 240.0) -> str:
    """Start ``papf argv`` piped; return its first stderr line matching ``pattern`` while it
    is still running, then stop it."""
    proc = warm.popen([sys.executable, "-m", "papf", *argv], cwd=cwd, stdout=subprocess.PIPE,
                      stderr=subprocess.PIPE)
    seen: list[str] = []
    try:
        line = stderr_until(proc, pattern, seen, timeout_s)
        assert proc.poll() is None, "the progress line came only at the end"
        return line.strip()
    finally:
        if proc.poll() is None:
            interrupt(proc, 30)
        proc.stdout.close()
        proc.stderr.close()


@pytest.mark.parametrize("argv, pattern", [
    (["experiment", "wang"], r"^wang: 1/\d+  fig "),
    (["experiment", "horizon"], r"^horizon: 1/9  apf default"),
    (["experiment", "deviations", "--n", "1"], r"^deviations: 1/\d+  default on "),
    (["experiment", "test1-sweep", "--seeds", "0"], r"^test1-sweep: 1/\d+  side "),
])
def test_studies_print_a_line_per_run(tmp_path, argv, pattern):
    _first_progress([*argv, "--out", str(tmp_path / "out")], pattern, tmp_path)


def test_run_view_prints_the_url_without_realtime(tmp_path):
    port = free_port()
    line = _first_progress(["run", "--world", "open", "--view", str(port), "--timeout", "20"],
                           r"live view on ws://", tmp_path)
    assert f"ws://127.0.0.1:{port}" in line and "--realtime" in line


@pytest.mark.slow   # the slow tier (make test-quick leaves it out)
def test_animate_prints_progress_before_its_last_line(tmp_path):
    rec, out = tmp_path / "run.mcap", tmp_path / "run.gif"
    write_drive(rec, 100, {"world": "open", "planner": "apf", "seed": 0})
    proc = subprocess.run([sys.executable, "-m", "papf", "animate", str(rec), str(out),
                           "--speed", "2", "--fps", "10"], cwd=tmp_path, text=True,
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=240)
    lines = proc.stdout.strip().splitlines()
    assert proc.returncode == 0, lines[-10:]
    progress = [n for n, line in enumerate(lines) if line.startswith("animate run.gif: ")]
    assert len(progress) >= 5 and progress[-1] < len(lines) - 1, lines
    assert lines[-1].startswith(f"{out}: 11 frames")
