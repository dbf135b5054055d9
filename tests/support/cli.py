"""The ``papf`` command run as a process, as a user runs it (the CLI tests of every tier)."""

from __future__ import annotations

import subprocess
import sys


def papf(*args, timeout: float = 60) -> subprocess.CompletedProcess:
    """``python -m papf ARGS`` with no stdin; its exit code, stdout and stderr (text)."""
    return subprocess.run([sys.executable, "-m", "papf", *map(str, args)], capture_output=True,
                          text=True, timeout=timeout, stdin=subprocess.DEVNULL)
