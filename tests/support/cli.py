"""The ``papf`` command run as a process, as a user runs it (the CLI tests of every tier)."""

from __future__ import annotations

import subprocess
import sys

from tests.support import warm


def papf(*args, timeout: float = 60, cwd=None) -> subprocess.CompletedProcess:
    """``python -m papf ARGS`` with no stdin; its exit code, stdout and stderr (text). A fork
    of the test worker's warm interpreter (:mod:`tests.support.warm`)."""
    return warm.run([sys.executable, "-m", "papf", *args], timeout=timeout, cwd=cwd)


def stderr_until(proc: subprocess.Popen, pattern: str, seen: list[str],
                 timeout_s: float = 60.0) -> str:
    """The first line of ``proc``'s stderr (a text pipe) that matches the regular expression
    ``pattern``; every line read is appended to ``seen``. AssertionError when the stream
    ends or ``timeout_s`` passes first (checked between lines)."""
    import re
    import time

    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        line = proc.stderr.readline()
        if not line:
            break
        seen.append(line.rstrip())
        if re.search(pattern, line):
            return line
    raise AssertionError(f"no line /{pattern}/ in {seen[-10:]}")


def interrupt(proc, timeout_s: float) -> bool:
    """Ctrl-C to ``proc``'s process group (SIGINT), SIGKILL after ``timeout_s`` [s] if it
    still runs; whether it stopped on the SIGINT (a process that had ended: True)."""
    import contextlib
    import os
    import signal

    with contextlib.suppress(ProcessLookupError):
        os.killpg(proc.pid, signal.SIGINT)
    try:
        proc.wait(timeout=timeout_s)
        return True
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait(timeout=30)
        return False
