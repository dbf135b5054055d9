"""Helpers for end-to-end tests that run `papf run` as a real process tree."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from pathlib import Path

from papf.launch.supervisor import free_port

RUN_TIMEOUT_S = 240  # hard wall-clock limit of one `papf run` in a test


def papf_run(*args: str, port: int | None = None, timeout: float = RUN_TIMEOUT_S):
    """Run `papf run ... --json --port P`; return (exit code, parsed JSON or None, stderr)."""
    port = port or free_port()
    cmd = [sys.executable, "-m", "papf", "run", *args, "--json", "--port", str(port)]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    try:
        out, err = proc.communicate(timeout=timeout)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    result = json.loads(out.strip().splitlines()[-1]) if out.strip() else None
    return proc.returncode, result, err


def start_papf_run(*args: str, port: int, **popen) -> subprocess.Popen:
    cmd = [sys.executable, "-m", "papf", "run", *args, "--json", "--port", str(port)]
    return subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True, **popen)


def pids_of(module: str, port: int) -> list[int]:
    """PIDs of `python -m <module> ... tcp/127.0.0.1:<port>` processes (from /proc)."""
    pids = []
    for d in Path("/proc").iterdir():
        if not d.name.isdigit():
            continue
        try:
            argv = (d / "cmdline").read_bytes().split(b"\0")
        except OSError:
            continue
        text = [a.decode(errors="replace") for a in argv]
        if module in text and any(a.endswith(f":{port}") for a in text):
            pids.append(int(d.name))
    return pids
