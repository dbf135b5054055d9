"""A warm process that forks the nodes: each node's interpreter and imports paid once per run.

A node started as ``python -m nodes.planner …`` pays for its interpreter, numpy, Zenoh,
the messages and its own imports — 0.15–0.25 s of CPU — and a PAPF planner also loads
numba and its compiled kernels, about 0.5 s more. A fleet of 16 planners paid that 16 times
over on two cores. The launcher's :class:`~papf.launch.supervisor.Supervisor` starts one
fork server per run instead (``python -m papf.launch.forkserver``): it imports what every
node shares, and each node's top imports before forking the first node of that kind (read
from its ``__main__``'s source, never run in the server). A node's package may say what
else to load ahead (``preload(argv)`` in its ``preload.py``: imports it makes later and
compiled kernels, nothing else — the PAPF kernels): the server loads that before the second
node of the kind, so the first loads it itself, side by side with the others' start.
Every node is still a process of its own, with its own Zenoh session and everything else a
``python -m`` start gives it:

- its own session and process group (a stop reaches all it spawns), its standard output
  and error one pipe the launcher reads, standard input ``/dev/null`` (or the three streams
  a request brings: the tests fork ``papf`` commands so, ``tests/support/warm.py``), the environment,
  working directory and argv of the request, and that command line in ``/proc/<pid>/cmdline``
  (``ps``, ``pgrep -f``), written over the server's own, which is padded to make room;
- the same exit as ``python -m``: an exception is printed and exits 1, ``sys.exit(n)``
  exits ``n``, and the interpreter's own shutdown runs;
- the server's child: the server reaps it and reports its exit code to the launcher on the
  control socket (:class:`ForkedProc` reads it as ``Popen.poll`` would). A node dies with the
  server (``PR_SET_PDEATHSIG``), which dies with the launcher, or leaves when the launcher
  closes the socket.

The server is single-threaded when it forks (nothing it imports starts a thread: OpenBLAS
is held to one by ``common``; a server that finds a second thread forks nothing more, and
the launcher starts the rest by ``python -m``) and it never opens a Zenoh session, so a
node's runtime starts fresh in the node. Its control socket is an unnamed socket pair whose
other end only the launcher holds: nothing else can ask it for a process. A node whose
interpreter-start variables (``STARTUP_VARS``) differ from the server's, or whose command
line does not fit the room, is started by ``python -m`` as before; so is every node with
``PAPF_FORK_SERVER=0``, and everywhere but Linux.
"""

from __future__ import annotations

import ast
import contextlib
import ctypes
import gc
import importlib
import importlib.util
import io
import json
import logging
import os
import runpy
import selectors
import signal
import socket
import subprocess
import sys
import threading
import time

ENV = "PAPF_FORK_SERVER"          # "0": no fork server (nodes started by python -m)
MAX_REQUEST = 1 << 20             # [bytes] one request: argv, environment, working directory
GONE_CODE = 255                   # a node's exit code where its server died before it did
TITLE_ROOM = 4096                 # [bytes] the server's padded command line: a node's fits in it
SHARED = ("common", "numpy", "zenoh", "common.transport", "schemas.messages")
# variables read when the interpreter or a library starts (the server's own start): a node
# whose values differ is started by python -m instead
STARTUP_VARS = ("PYTHON", "NUMBA_", "OPENBLAS_", "OMP_", "MKL_", "LD_", "MALLOC_")
_PR_SET_PDEATHSIG = 1


def die_with_parent() -> None:
    """This process gets SIGTERM when its parent (thread) dies (``PR_SET_PDEATHSIG``): a
    node of the supervisor (between fork and exec), the fork server, a forked node."""
    with contextlib.suppress(OSError, AttributeError):
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(_PR_SET_PDEATHSIG, signal.SIGTERM, 0, 0, 0)


def enabled() -> bool:
    """Whether nodes are forked (Linux, and not turned off by ``PAPF_FORK_SERVER=0``)."""
    return sys.platform.startswith("linux") and os.environ.get(ENV, "1") != "0"


def _startup_vars(env: dict) -> dict:
    return {k: v for k, v in env.items() if k.startswith(STARTUP_VARS)}


def _title(argv: list[str]) -> bytes:
    """The NUL-separated command line of ``python -m argv…``, as the kernel shows it."""
    return b"".join(os.fsencode(a) + b"\0" for a in [sys.executable, "-m", *argv])


# -- the launcher's side -----------------------------------------------------------------

class ForkedProc:
    """A forked node, as the launcher sees it: the parts of ``subprocess.Popen`` the
    supervisor uses (``pid``, ``stdout``, ``poll``, ``wait``, ``returncode``); the exit code
    is the one the server reports."""

    def __init__(self, pid: int, stdout: io.TextIOBase, server: ForkServer):
        self.pid, self.stdout, self._server = pid, stdout, server
        self.returncode: int | None = None

    def poll(self) -> int | None:
        if self.returncode is None:
            self._server.check_gone(self)
        return self.returncode

    def wait(self, timeout: float | None = None) -> int:
        """Its exit code; ``subprocess.TimeoutExpired`` after ``timeout`` [s] (None: forever)."""
        deadline = None if timeout is None else time.monotonic() + timeout
        while self.poll() is None:
            left = None if deadline is None else deadline - time.monotonic()
            if left is not None and left <= 0:
                raise subprocess.TimeoutExpired(f"pid {self.pid}", timeout)
            self._server.wait_exit(self, 0.5 if left is None else min(left, 0.5))
        return self.returncode   # type: ignore[return-value]


class ForkServer:
    """The launcher's handle on its fork server: :meth:`spawn` a node, :meth:`close`."""

    def __init__(self, argv: list[str], env: dict, stderr=None, preexec_fn=None, cwd=None):
        """Start the server: ``argv`` runs this module (``python -m papf.launch.forkserver``;
        the control socket's fd and the title's room are appended), with environment ``env``,
        in ``cwd`` (None: this process's working directory)."""
        self._sock, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        self._startup = _startup_vars(env)
        self._lock = threading.Lock()            # one request at a time
        self._cond = threading.Condition()       # the answers and exits the reader files
        self._answers: list[dict] = []
        self._live: dict[int, ForkedProc] = {}   # by pid: the nodes still running
        self._early: dict[int, int] = {}         # exit codes that came before their node's answer
        self._gone = False
        self.proc = subprocess.Popen(
            [*argv, str(theirs.fileno()), " " * TITLE_ROOM], stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL, stderr=stderr, pass_fds=(theirs.fileno(),),
            start_new_session=True, preexec_fn=preexec_fn, env=env, cwd=cwd)
        theirs.close()
        threading.Thread(target=self._read, daemon=True, name="forkserver-reader").start()

    @property
    def gone(self) -> bool:
        """Whether the server has closed its end (exited)."""
        return self._gone

    def can_fork(self, argv: list[str], env: dict) -> bool:
        """Whether ``python -m argv…`` with environment ``env`` can be forked: the variables
        read at an interpreter's or a library's start are the server's (``STARTUP_VARS``)
        and its command line fits the room."""
        return (_startup_vars(env) == self._startup
                and len(_title(argv)) <= TITLE_ROOM)

    def spawn(self, argv: list[str], env: dict, cwd: str | None = None,
              streams: tuple[int, int, int] | None = None) -> ForkedProc:
        """Fork ``python -m argv[0] argv[1:]`` with environment ``env`` in ``cwd`` (None:
        this process's working directory). Its output and errors: one pipe, the returned
        process's ``stdout``; or with ``streams``, the descriptors (input, output, errors)
        given, left open here (``stdout`` None). OSError when the server cannot (it has gone)."""
        request = json.dumps({"argv": argv, "env": env, "cwd": cwd or os.getcwd()}).encode()
        if len(request) > MAX_REQUEST:
            raise OSError(f"a fork request of {len(request)} bytes (at most {MAX_REQUEST})")
        r, w = os.pipe() if streams is None else (None, None)
        try:
            with self._lock:
                socket.send_fds(self._sock, [request], [w] if streams is None else list(streams))
                answer = self._answer()
        finally:
            if w is not None:
                os.close(w)
        if "pid" not in answer:
            if r is not None:
                os.close(r)
            raise OSError(answer.get("error", "no answer"))
        stdout = None if r is None else io.TextIOWrapper(
            io.FileIO(r, "r"), encoding="utf-8", errors="replace", line_buffering=True)
        proc = ForkedProc(int(answer["pid"]), stdout, self)
        with self._cond:   # an exit reported before this line is the node's own
            proc.returncode = self._early.pop(proc.pid, None)
            if proc.returncode is None:
                self._live[proc.pid] = proc
        return proc

    def _answer(self) -> dict:
        with self._cond:
            self._cond.wait_for(lambda: self._answers or self._gone)
            return self._answers.pop(0) if self._answers else {"error": "the fork server has gone"}

    def _read(self) -> None:
        """The server's messages: answers to requests, and its nodes' exits."""
        while True:
            try:
                data = self._sock.recv(4096)
            except OSError:
                data = b""
            with self._cond:
                if not data:
                    self._gone = True
                    self._cond.notify_all()
                    return
                message = json.loads(data)
                if "exit" in message:
                    pid, code = int(message["exit"]), int(message["code"])
                    if pid in self._live:
                        self._live.pop(pid).returncode = code
                    else:
                        self._early[pid] = code
                else:
                    self._answers.append(message)
                self._cond.notify_all()

    def check_gone(self, proc: ForkedProc) -> None:
        """Where the server has gone, its nodes died with it (``PR_SET_PDEATHSIG``) and
        nobody reports their exit codes: one that has left /proc gets ``GONE_CODE``."""
        with self._cond:
            if self._gone and proc.returncode is None and not os.path.exists(f"/proc/{proc.pid}"):
                self._live.pop(proc.pid, None)
                proc.returncode = GONE_CODE

    def wait_exit(self, proc: ForkedProc, timeout: float) -> None:
        """Until the server reports an exit (``proc``'s or another's), or ``timeout`` [s]."""
        with self._cond:   # its exit code is filed under this lock: no wake-up is missed
            if proc.returncode is None:
                self._cond.wait(min(timeout, 0.05) if self._gone else timeout)

    def close(self, timeout_s: float = 2.0) -> None:
        """End the server (and any node still running: they die with it)."""
        with contextlib.suppress(OSError):
            self._sock.shutdown(socket.SHUT_RDWR)
        try:
            self.proc.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        with contextlib.suppress(OSError):
            self._sock.close()


# -- the server ------------------------------------------------------------------------

def top_imports(module: str) -> list[str]:
    """The modules ``python -m module`` imports at its top: those of its ``__main__``'s (or
    the module's) first level, found by reading the source (ast), never by running it."""
    spec = importlib.util.find_spec(module)
    if spec is not None and spec.submodule_search_locations is not None:
        spec = importlib.util.find_spec(f"{module}.__main__")
    if spec is None or not spec.origin or not spec.origin.endswith(".py"):
        return []
    with open(spec.origin, encoding="utf-8") as f:
        tree = ast.parse(f.read(), spec.origin)
    package = spec.parent or ""
    names = []
    for stmt in tree.body:
        if isinstance(stmt, ast.Import):
            names += [alias.name for alias in stmt.names]
        elif isinstance(stmt, ast.ImportFrom) and stmt.module != "__future__":
            base = "." * stmt.level + (stmt.module or "")
            names.append(importlib.util.resolve_name(base, package) if stmt.level else base)
    return names


def _preload(module: str, args: list[str], seen: set[str], log: logging.Logger) -> None:
    """Load ahead what the node ``python -m module args…`` will. Before the first node of
    its kind (``seen``: the kinds forked before): the modules its top imports
    (:func:`top_imports`). From the second on: ``preload(args)`` of its package's
    ``preload`` module if it has one (what it imports later, or compiles: the PAPF kernels);
    the first loads that itself, on the other core while the server goes on forking, so a
    run of one robot starts as fast as before and a fleet loads it twice, not once per
    robot. A failure is logged and left for the node to meet (it imports the same)."""
    try:
        if module not in seen:
            for name in top_imports(module):
                importlib.import_module(name)
        else:
            spec = importlib.util.find_spec(module)
            if spec is not None and spec.submodule_search_locations is not None \
                    and importlib.util.find_spec(f"{module}.preload") is not None:
                importlib.import_module(f"{module}.preload").preload(args)
    except Exception as e:   # noqa: BLE001 - the node reports it itself when it starts
        log.warning("preload of %s: %s: %s", module, type(e).__name__, e)
    seen.add(module)


def serve(sock: socket.socket) -> dict:
    """Answer fork requests and report the nodes' exits until the launcher closes its end
    (then exit). Returns only in a forked node, with its request (its fds in place)."""
    log = logging.getLogger("forkserver")
    for name in SHARED:
        try:
            importlib.import_module(name)
        except Exception as e:   # noqa: BLE001 - each node imports it again and says why
            log.warning("import of %s: %s: %s", name, type(e).__name__, e)
    wake_r, wake_w = os.pipe()
    os.set_blocking(wake_w, False)
    signal.set_wakeup_fd(wake_w)
    signal.signal(signal.SIGCHLD, lambda *_: None)   # a handler, so that the wake-up fd hears it
    seen: set[str] = set()   # the kinds of node forked so far
    sel = selectors.DefaultSelector()
    sel.register(sock, selectors.EVENT_READ)
    sel.register(wake_r, selectors.EVENT_READ)
    while True:
        for key, _ in sel.select():
            if key.fileobj == wake_r:
                with contextlib.suppress(BlockingIOError):
                    os.read(wake_r, 512)
                _report_exits(sock)
                continue
            try:
                data, fds, _flags, _addr = socket.recv_fds(sock, MAX_REQUEST, 3)
            except OSError:
                data, fds = b"", []
            if not data:
                sys.exit(0)
            request = _fork(sock, data, fds, seen, log)
            if request is not None:   # the node
                sel.close()
                signal.set_wakeup_fd(-1)
                for fd in (wake_r, wake_w):
                    os.close(fd)
                return request


def _report_exits(sock: socket.socket) -> None:
    while True:
        try:
            pid, status = os.waitpid(-1, os.WNOHANG)
        except ChildProcessError:
            return
        if pid == 0:
            return
        with contextlib.suppress(OSError):
            sock.send(json.dumps({"exit": pid, "code": os.waitstatus_to_exitcode(status)}).encode())


def _fork(sock: socket.socket, data: bytes, fds: list[int], seen: set[str],
          log: logging.Logger) -> dict | None:
    """Fork the node of one request: its request in the node, None in the server (which
    has answered with the node's pid, or why not)."""
    try:
        if len(fds) not in (1, 3):
            raise ValueError("a request comes with one descriptor, its output and errors, or "
                             f"three, its input, output and errors; this one had {len(fds)}")
        request = json.loads(data)
        _preload(request["argv"][0], request["argv"][1:], seen, log)
        threads = len(os.listdir("/proc/self/task"))
        if threads > 1:   # a fork keeps only this thread: locks the others held stay held
            raise RuntimeError(f"it has {threads} threads after loading {request['argv'][0]} "
                               "(something it imported started one): a fork of it is unsafe")
        gc.freeze()   # what is loaded stays out of every node's collections (and shared)
        pid = os.fork()
    except Exception as e:   # noqa: BLE001 - the launcher starts it another way
        for fd in fds:
            os.close(fd)
        sock.send(json.dumps({"error": f"{type(e).__name__}: {e}"}).encode())
        return None
    if pid == 0:
        request["server"] = os.getppid()
        sock.close()
        streams = (None, fds[0], fds[0]) if len(fds) == 1 else fds
        for target, fd in enumerate(streams):
            if fd is not None:
                os.dup2(fd, target)
        for fd in set(fds) - {0, 1, 2}:
            os.close(fd)
        request["streams"] = len(fds) == 3
        return request
    for fd in fds:
        os.close(fd)
    sock.send(json.dumps({"pid": pid}).encode())
    return None


def _set_cmdline(title: bytes) -> None:
    """Write ``title`` over this process's command line (``/proc/self/cmdline``), NUL-padded
    to the room it has: where it does not fit, the command line stays the server's."""
    with contextlib.suppress(OSError, ValueError, IndexError):
        with open("/proc/self/stat", "rb") as f:
            fields = f.read().rsplit(b")", 1)[1].split()
        start, end = int(fields[45]), int(fields[46])   # arg_start, arg_end (proc(5): 48, 49)
        if start and end - start >= len(title):
            ctypes.memmove(start, title.ljust(end - start, b"\0"), end - start)


def become(request: dict) -> None:
    """In the forked node: its own session, dying with the server, the request's environment,
    directory, argv, command line and fresh standard streams."""
    os.setsid()
    die_with_parent()
    if os.getppid() != request["server"]:   # the server died meanwhile
        os._exit(1)
    if not request.get("streams"):
        with open(os.devnull, "rb") as null:
            os.dup2(null.fileno(), 0)
    signal.signal(signal.SIGINT, signal.default_int_handler)
    for sig in (signal.SIGTERM, signal.SIGCHLD, signal.SIGHUP):
        signal.signal(sig, signal.SIG_DFL)
    os.chdir(request["cwd"])
    os.environ.clear()
    os.environ.update(request["env"])
    if request.get("streams"):
        _streams_as_python_makes_them()
    else:   # a node: every line reaches the launcher as it is written
        sys.stdin = io.TextIOWrapper(io.FileIO(0, "r", closefd=False), encoding="utf-8")
        sys.stdout, sys.stderr = (
            io.TextIOWrapper(io.FileIO(fd, "w", closefd=False), encoding="utf-8",
                             errors="backslashreplace", line_buffering=True, write_through=True)
            for fd in (1, 2))
    sys.__stdout__, sys.__stderr__, sys.__stdin__ = sys.stdout, sys.stderr, sys.stdin
    logging.root.handlers.clear()
    sys.argv = list(request["argv"])
    if not sys.flags.safe_path:   # as `python -m` puts it: its working directory (the
        sys.path[0] = os.getcwd()   # server's own is there); with PYTHONSAFEPATH, nothing
    _set_cmdline(_title(request["argv"]))


def _streams_as_python_makes_them() -> None:
    """``sys.stdin``/``stdout``/``stderr`` on descriptors 0-2 as an interpreter started on
    them makes them: with the server's own settings (its streams are no terminal: output
    block-buffered, errors by line), and output by line where it is a terminal — a command
    that forgets to flush shows it as it would started by ``python -m``."""
    made = []
    for fd, like in ((0, sys.__stdin__), (1, sys.__stdout__), (2, sys.__stderr__)):
        raw = io.FileIO(fd, "r" if fd == 0 else "w", closefd=False)
        made.append(io.TextIOWrapper(
            io.BufferedReader(raw) if fd == 0 else io.BufferedWriter(raw), encoding=like.encoding,
            errors=like.errors, line_buffering=like.line_buffering or (fd == 1 and raw.isatty()),
            write_through=like.write_through))
    sys.stdin, sys.stdout, sys.stderr = made


def main() -> None:
    sock = socket.socket(fileno=int(sys.argv[-2]))
    request = serve(sock)
    become(request)
    runpy.run_module(request["argv"][0], run_name="__main__", alter_sys=True)


if __name__ == "__main__":
    main()
