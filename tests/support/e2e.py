"""Helpers for end-to-end tests that run `papf run` as a real process tree."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
from contextlib import contextmanager
from pathlib import Path

from papf.launch.supervisor import free_port
from tests.support import warm

RUN_TIMEOUT_S = 240  # hard wall-clock limit of one `papf run` in a test


def papf_run(*args: str, port: int | None = None, timeout: float = RUN_TIMEOUT_S):
    """Run `papf run ... --json --port P`; return (exit code, parsed JSON or None, stderr).

    Without ``port``, a free one is picked, and picked again (once) when the run
    refuses it because something listens there by then: another test's router picked the
    same free port between this pick and the bind (free_port's race; seen once in a suite
    run with the traffic test three times over)."""
    for _ in range(2):
        code, result, err = _papf_run(args, port or free_port(), timeout)
        if port is not None or code != 2 or "already listens" not in err:
            break
    return code, result, err


def _papf_run(args: tuple[str, ...], port: int, timeout: float):
    proc = start_papf_run(*args, port=port)
    try:
        out, err = proc.communicate(timeout=timeout)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    result = json.loads(out.strip().splitlines()[-1]) if out.strip() else None
    return proc.returncode, result, err


def start_papf_run(*args: str, port: int, **popen) -> subprocess.Popen | warm.Proc:
    """``papf run ARGS --json --port PORT``, output and errors piped: forked from the warm
    interpreter (tests/support/warm.py), or a process of its own where ``popen`` asks for
    more of ``subprocess.Popen`` (a ``preexec_fn``: a launcher started with SIGINT ignored)."""
    cmd = [sys.executable, "-m", "papf", "run", *args, "--json", "--port", str(port)]
    if not popen:
        return warm.popen(cmd)
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


class Batteries:
    """The battery states a meter publishes, collected from a subscriber's thread."""

    def __init__(self):
        self.items: list = []
        self.lock = threading.Lock()

    def add(self, sample) -> None:
        """Subscriber callback: decode and keep one ``BatteryState``."""
        from schemas import BatteryState

        with self.lock:
            self.items.append(BatteryState.from_bytes(sample.payload.to_bytes()))

    def wait_for(self, stamp_ns: int, timeout_s: float = 30.0) -> None:
        """Return once the latest state is stamped ``stamp_ns`` [ns] or later, or after
        ``timeout_s`` [s] (the meter's last states may still be coming)."""
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            with self.lock:
                if self.items and self.items[-1].stamp_ns >= stamp_ns:
                    return
            time.sleep(0.05)


NODES = ("nodes.world_sim", "nodes.lidar_sim", "nodes.planner", "nodes.energy_meter",
         "papf.launch.router")


def assert_no_orphans(port):
    """No process of a `papf run` on ``port`` (its nodes, its router) is left after it ends."""
    deadline = time.monotonic() + 30     # bounds a hang: a loaded machine reaps slowly
    while time.monotonic() < deadline:
        left = {m: pids_of(m, port) for m in NODES}
        if not any(left.values()):
            return
        time.sleep(0.1)
    raise AssertionError(f"processes left behind: {left}")


@contextmanager
def metered_bus(spawn, ns: str):
    """A router and a fresh energy-meter process (motor model) in namespace ``ns``, started
    with ``spawn`` (the conftest fixture); yields a client session and the :class:`Batteries`
    the meter publishes."""
    import zenoh

    from common.transport import wait_alive, zenoh_config
    from papf.launch.supervisor import wait_port
    from schemas import Keys

    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    spawn("router", [sys.executable, "-m", "papf.launch.router", "--listen", endpoint])
    assert wait_port(port, 15)
    with zenoh.open(zenoh_config("client", [endpoint])) as s:
        spawn("energy_meter", [sys.executable, "-m", "nodes.energy_meter", "--connect", endpoint,
                               "--namespace", ns, "--model", "motor"])
        assert not wait_alive(s, Keys(ns), ["energy_meter"], timeout_s=30)
        got = Batteries()
        sub = s.declare_subscriber(Keys(ns).battery, got.add)
        try:
            yield s, got
        finally:
            sub.undeclare()


def running(tag: str) -> list[str]:
    """Command lines of this host's processes (not this one) that contain ``tag``."""
    found = []
    for pid in filter(str.isdigit, os.listdir("/proc")):
        try:
            cmd = Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode()
        except OSError:
            continue
        if tag in cmd and int(pid) != os.getpid():
            found.append(cmd)
    return found


def leftovers(tag: str, timeout_s: float = 30.0) -> list[str]:
    """Processes whose command line contains ``tag`` (a test's unique namespace) still
    running after ``timeout_s`` (a process being stopped may take a moment to go)."""
    deadline = time.monotonic() + timeout_s
    while (found := running(tag)) and time.monotonic() < deadline:
        time.sleep(0.1)
    return found
