"""``python -m papf …`` for the tests, forked from a warm interpreter (one per test worker);
so are ``python -m`` of our other modules (the router of the bus tests).

The suite runs the ``papf`` command hundreds of times, and each start paid for an
interpreter and its imports (numpy, Zenoh, the messages, the CLI, matplotlib for the
commands that draw) on two cores shared by four test workers. Here each
worker starts one server the first time it needs one — :mod:`papf.launch.forkserver`, the
launcher's own, after :data:`PRELOAD` — and each command is a fork of it: still a process of
its own (its own session and process group, pid, exit code, the environment, working
directory and arguments of the call, ``/proc/<pid>/cmdline`` and ``sys.path[0]`` as ``python
-m`` gives them), with its input, output and errors where the call says. What it imports
that the server had loaded is already there; nothing else differs. A call the server cannot
take (an interpreter-start variable of its own, no server) runs ``python -m`` as before;
``PAPF_TEST_FORK=0`` runs them all so.
"""

from __future__ import annotations

import atexit
import contextlib
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

from papf.launch import forkserver

ROOT = Path(__file__).resolve().parents[2]
ENV = "PAPF_TEST_FORK"
PAPF = [sys.executable, "-m", "papf"]
PACKAGES = ("papf", "nodes")   # python -m of a module of these is forked (the rest: python -m)

_server: forkserver.ForkServer | None = None
_lock = threading.Lock()


def _get_server() -> forkserver.ForkServer | None:
    global _server
    with _lock:
        if _server is None or _server.gone:
            if os.environ.get(ENV, "1") == "0" or not forkserver.enabled():
                return None
            # no PR_SET_PDEATHSIG: a test's thread may be the first caller, and the server
            # must outlive it; it leaves when this process closes its end of the socket
            _server = forkserver.ForkServer([sys.executable, "-m", "tests.support.warm_server"],
                                            dict(os.environ), stderr=subprocess.DEVNULL, cwd=ROOT)
            atexit.register(_server.close)
        return _server


class Proc:
    """A forked ``papf`` command, as much of ``subprocess.Popen`` as the tests use: ``pid``,
    ``args``, ``returncode``, ``stdout``/``stderr`` (text, where piped), ``poll``, ``wait``,
    ``communicate``, ``send_signal``, ``terminate``, ``kill``."""

    def __init__(self, args: list[str], forked: forkserver.ForkedProc, out: int | None,
                 err: int | None):
        self.args, self._forked, self.pid = args, forked, forked.pid
        self.stdout, self.stderr = (None if fd is None else open(fd, encoding="utf-8",
                                                                 errors="replace")
                                    for fd in (out, err))
        self.stdin = None
        self._readers: dict[str, tuple[threading.Thread, list[str]]] = {}   # communicate's

    @property
    def returncode(self) -> int | None:
        return self._forked.returncode

    def poll(self) -> int | None:
        return self._forked.poll()

    def wait(self, timeout: float | None = None) -> int:
        return self._forked.wait(timeout)

    def send_signal(self, sig: int) -> None:
        if self.poll() is None:
            with contextlib.suppress(ProcessLookupError):
                os.kill(self.pid, sig)

    def terminate(self) -> None:
        self.send_signal(signal.SIGTERM)

    def kill(self) -> None:
        self.send_signal(signal.SIGKILL)

    def communicate(self, timeout: float | None = None) -> tuple[str | None, str | None]:
        """Its output and errors (text) to their ends, and its exit;
        ``subprocess.TimeoutExpired`` after ``timeout`` [s] (it keeps running and a later
        call goes on, as Popen's). One reader thread per pipe, as Popen's where it cannot
        poll: what a test read line by line before is not read twice."""
        deadline = None if timeout is None else time.monotonic() + timeout
        if not self._readers:
            for name in ("stdout", "stderr"):
                stream = getattr(self, name)
                if stream is not None:
                    chunks: list[str] = []
                    reader = threading.Thread(target=self._drain, args=(stream, chunks),
                                              daemon=True)
                    reader.start()
                    self._readers[name] = (reader, chunks)
        for reader, _ in self._readers.values():
            reader.join(None if deadline is None else max(deadline - time.monotonic(), 0.0))
            if reader.is_alive():
                raise subprocess.TimeoutExpired(self.args, timeout)
        self.wait(None if deadline is None else max(deadline - time.monotonic(), 0.1))
        text = {name: "".join(chunks) for name, (_, chunks) in self._readers.items()}
        return text.get("stdout"), text.get("stderr")

    @staticmethod
    def _drain(stream, chunks: list) -> None:
        with stream:
            chunks.append(stream.read())


def popen(args: list, *, cwd=None, env: dict | None = None, stdout=subprocess.PIPE,
          stderr=subprocess.PIPE):
    """``subprocess.Popen(args, stdin=DEVNULL, start_new_session=True, text=True, …)`` of a
    ``python -m papf`` command (or a module of :data:`PACKAGES`), forked where it can be
    (:class:`Proc`), else that Popen."""
    args = [str(a) for a in args]
    env_ = dict(os.environ if env is None else env)
    def python_m():
        return subprocess.Popen(args, cwd=cwd, env=env, stdout=stdout, stderr=stderr,
                                stdin=subprocess.DEVNULL, start_new_session=True, text=True)

    ours = len(args) > 2 and args[:2] == PAPF[:2] and args[2].split(".")[0] in PACKAGES
    server = _get_server() if ours else None
    if server is None or not server.can_fork(args[2:], env_):
        return python_m()
    ends, mine = [], []
    for own, where in ((1, stdout), (2, stderr)):
        if where == subprocess.PIPE:
            r, w = os.pipe()
            ends.append(w)
            mine.append(r)
            continue
        if where == subprocess.DEVNULL:
            ends.append(os.open(os.devnull, os.O_WRONLY))
        else:     # None: this process's own, as Popen's child inherits it; else a file's
            ends.append(os.dup(own if where is None else
                               where.fileno() if hasattr(where, "fileno") else where))
        mine.append(None)
    null = os.open(os.devnull, os.O_RDONLY)
    try:
        forked = server.spawn(args[2:], env_, cwd=str(cwd or os.getcwd()),
                              streams=(null, *ends))
    except OSError:   # the server has gone: python -m, as the launcher's nodes then
        for fd in [r for r in mine if r is not None]:
            os.close(fd)
        return python_m()
    finally:
        for fd in (null, *ends):
            os.close(fd)
    return Proc(args, forked, *mine)


def run(args: list, *, cwd=None, env: dict | None = None,
        timeout: float = 60) -> subprocess.CompletedProcess:
    """``subprocess.run(args, capture_output=True, text=True, stdin=DEVNULL, timeout=…)`` of
    a ``python -m papf`` command, forked where it can be; on a timeout its process group is
    killed and ``subprocess.TimeoutExpired`` raised, as ``subprocess.run`` does."""
    proc = popen(args, cwd=cwd, env=env)
    try:
        out, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
        raise
    return subprocess.CompletedProcess(args, proc.returncode, out, err)
