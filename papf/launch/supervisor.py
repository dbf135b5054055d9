"""Start node processes, prefix their logs, and stop them all — no orphans.

Each child runs in its own process group (so a stop reaches anything it spawned)
and, on Linux, gets SIGTERM from the kernel if the supervisor itself dies
(``PR_SET_PDEATHSIG``), so even a SIGKILLed launcher leaves no node behind.
"""

from __future__ import annotations

import contextlib
import os
import random
import signal
import socket
import subprocess
import sys
import threading
import time
from collections import deque
from dataclasses import dataclass, field
from typing import TextIO

from common.text import safe_line
from papf.launch import forkserver, portrange

PUMP_JOIN_S = 5.0   # [s wall] at most, after stop(), for the children's last output lines


@dataclass
class Child:
    name: str
    proc: subprocess.Popen | forkserver.ForkedProc
    tail: deque = field(default_factory=lambda: deque(maxlen=40))
    pump: threading.Thread | None = None   # copies its output to the log stream until EOF

    @property
    def returncode(self) -> int | None:
        return self.proc.poll()


# Python 3.10 has no PYTHONSAFEPATH: the module is run by a bootstrap that drops the
# working directory from sys.path first (what -P does from 3.11 on).
_SAFE_BOOT = ("import runpy, sys; sys.path[:] = [p for p in sys.path if p not in ('', '.')]; "
              "sys.argv[0] = sys.argv[1]; del sys.argv[1]; "
              "runpy.run_module(sys.argv[0], run_name='__main__', alter_sys=True)")


def safe_argv(argv: list[str]) -> list[str]:
    """``argv`` so that the caller's working directory cannot shadow our packages: a
    ``./worlds/`` or ``./common/__init__.py`` where papf is started must not be imported by
    the nodes. ``python -m M`` puts the working directory first on sys.path; from 3.11 the
    child's ``PYTHONSAFEPATH=1`` (set by :meth:`Supervisor.start`) stops that, on 3.10 a
    bootstrap does."""
    if sys.version_info >= (3, 11) or len(argv) < 3 or argv[1] != "-m":
        return list(argv)
    return [argv[0], "-c", _SAFE_BOOT, argv[2], *argv[3:]]


class Supervisor:
    """Owns the node processes of one run. Use as a context manager."""

    def __init__(self, log_stream: TextIO | None = None, show=lambda name, line: True,
                 last: tuple[str, ...] = (), env: dict | None = None):
        self.children: list[Child] = []
        self.last = last  # names stopped after all others, in this order (see stop())
        self.log_stream = log_stream or sys.stderr
        self.show = show
        self.env = env or {}       # added to every child's environment (e.g. the run key)
        self._lock = threading.Lock()
        self._forks: forkserver.ForkServer | None = None   # started with the first node
        self._fork = forkserver.enabled()

    def start(self, name: str, argv: list[str], env: dict | None = None) -> Child:
        """Start ``argv`` (e.g. ``[python, -m, nodes.planner, ...]``) as node ``name``: a
        ``python -m`` of this interpreter forked by the run's fork server
        (:mod:`papf.launch.forkserver`), any other command as it is."""
        env = {**os.environ, "PYTHONUNBUFFERED": "1", "PYTHONSAFEPATH": "1",
               "PAPF_NODE_PROCESS": "1", **self.env,   # a bounded stop (common.transport)
               **(env or {})}
        proc = self._forked(argv, env) or subprocess.Popen(
            safe_argv(argv), stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
            start_new_session=True, preexec_fn=forkserver.die_with_parent, text=True, errors="replace",
            bufsize=1, env=env)
        child = Child(name, proc)
        self.children.append(child)
        child.pump = threading.Thread(target=self._pump, args=(child,), daemon=True,
                                      name=f"log-{name}")
        child.pump.start()
        return child

    def _pump(self, child: Child) -> None:
        for line in child.proc.stdout:  # type: ignore[union-attr]
            line = line.rstrip("\n")
            child.tail.append(line)
            if self.show(child.name, line):
                with self._lock:
                    print(f"[{child.name}] {safe_line(line)}", file=self.log_stream, flush=True)

    def _forked(self, argv: list[str], env: dict):
        """``argv`` forked by the fork server, or None: not a ``python -m``, one the server
        cannot fork (``ForkServer.can_fork``: this one is started as a process of its own),
        the server off or gone (so is every later one)."""
        if not (self._fork and len(argv) > 2 and argv[0] == sys.executable and argv[1] == "-m"):
            return None
        try:
            if self._forks is None:
                self._forks = forkserver.ForkServer(
                    safe_argv([sys.executable, "-m", "papf.launch.forkserver"]), env,
                    stderr=self._log_stream_fd(), preexec_fn=forkserver.die_with_parent)
            if self._forks.gone:
                raise OSError(f"it has exited with code {self._forks.proc.poll()}")
            if not self._forks.can_fork(argv[2:], env):
                return None
            return self._forks.spawn(argv[2:], env)
        except OSError as e:
            print(f"[launcher] nodes started without the fork server: {safe_line(str(e))}",
                  file=self.log_stream, flush=True)
            self._fork = False
            return None

    def _log_stream_fd(self):
        """Where the fork server's own warnings go: the log stream when it is a file."""
        try:
            return self.log_stream.fileno()
        except (AttributeError, OSError, ValueError):
            return subprocess.DEVNULL

    def dead(self) -> list[Child]:
        """Children that have exited."""
        return [c for c in self.children if c.returncode is not None]

    def death_reason(self) -> str:
        """'<name> exited with code N: <last log lines>' for the first dead child, or ''."""
        dead = self.dead()
        if not dead:
            return ""
        c = dead[0]
        tail = list(c.tail)    # a copy: its log thread may still be appending the last lines
        errors = [line.split(" ERROR ", 1)[-1].strip() for line in tail if " ERROR " in line]
        if errors:   # a node that says why it stops: that line, not its last six
            return f"{c.name} exited with code {c.returncode}: {errors[-1]}"
        return f"{c.name} exited with code {c.returncode}: " + " | ".join(tail[-6:])

    def stop(self, grace_s: float = 3.0, last: tuple[str, ...] = ()) -> None:
        """Stop every child: SIGTERM, then SIGKILL after ``grace_s``.

        Children named in ``last`` are stopped afterwards, one stage each in that order,
        each once the previous stage has exited — e.g. ``("recorder", "router")``: a recorder
        that has not closed its file yet (no ``run_ended``: an interrupted run) still gets
        every message the router forwards before the router goes.
        """
        stages = [[c for c in self.children if c.name not in last]]
        stages += [[c for c in self.children if c.name == name] for name in last]
        for stage in stages:
            _stop_stage(stage, grace_s)
        for child in self.children:  # a group may outlive its leader
            _signal_group(child.proc, signal.SIGKILL)
        if self._forks is not None:
            self._forks.close()
            self._forks = None
        deadline = time.monotonic() + PUMP_JOIN_S   # every last line printed before we return
        for child in self.children:
            if child.pump is not None:
                child.pump.join(max(0.0, deadline - time.monotonic()))

    def __enter__(self) -> Supervisor:
        return self

    def __exit__(self, *exc) -> None:
        self.stop(last=self.last)


def _stop_stage(children: list[Child], grace_s: float) -> None:
    for child in reversed(children):
        _signal_group(child.proc, signal.SIGTERM)
    deadline = time.monotonic() + grace_s
    for child in reversed(children):
        try:
            child.proc.wait(timeout=max(0.0, deadline - time.monotonic()))
        except subprocess.TimeoutExpired:
            _signal_group(child.proc, signal.SIGKILL)
            child.proc.wait(timeout=5)


def _signal_group(proc: subprocess.Popen, sig: int) -> None:
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(proc.pid, sig)


_PORTS = random.Random()   # its own generator: a seeded global one would repeat ports
FREE_PORT_SPAN = 12_000    # ports tried just below the kernel's ephemeral range


def _ephemeral_low() -> int:
    """The first port of the kernel's range for outgoing connections (Linux; else 32768)."""
    try:
        with open("/proc/sys/net/ipv4/ip_local_port_range") as f:
            return int(f.read().split()[0])
    except (OSError, ValueError, IndexError):
        return 32768


def free_port() -> int:
    """A TCP port on 127.0.0.1 that is free right now, for a router to listen on.

    Inside ``--port-range`` when one is set (:mod:`papf.launch.portrange`); else picked at
    random below the kernel's ephemeral range when there is room: a port of that range can
    be taken as the local end of any outgoing connection (every Zenoh session makes some)
    between this check and the router's bind, which then fails.
    """
    rng = portrange.current()
    if rng is not None:
        return portrange.free_in_range(rng)
    low = _ephemeral_low()
    if low - FREE_PORT_SPAN >= 1024:
        for _ in range(100):
            port = _PORTS.randrange(low - FREE_PORT_SPAN, low)
            with socket.socket() as s:
                try:
                    s.bind(("127.0.0.1", port))
                except OSError:
                    continue
            if not port_in_use(port):
                return port
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def run_port() -> int:
    """The router port of one run of an experiment: its ``--port`` when given (the runs go
    one at a time), else :func:`free_port`."""
    return portrange.fixed_port() or free_port()


def port_in_use(port: int, host: str = "127.0.0.1") -> bool:
    with socket.socket() as s:
        return s.connect_ex((host, port)) == 0


def wait_port(port: int, timeout_s: float, host: str = "127.0.0.1", abort=lambda: False) -> bool:
    """Wait until something accepts TCP connections on ``host:port``."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline and not abort():
        if port_in_use(port, host):
            return True
        time.sleep(0.02)
    return False
