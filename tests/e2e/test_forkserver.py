"""The launcher's fork server (papf/launch/forkserver.py): a node it forks behaves as one
started by ``python -m`` — its output, exit code, environment, directory, argv, session,
ps title — and is the launcher's child, dying with it; the ways around it still work."""

import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest

from papf.launch import forkserver
from papf.launch.supervisor import Supervisor
from tests.support.e2e import papf_run

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="Linux only")

NODE = """
import os, sys, time
import probe_pre
print("argv", sys.argv[1:], flush=True)
print("cwd", os.getcwd(), flush=True)
print("env", os.environ.get("PROBE_VALUE"), flush=True)
print("ppid", os.getppid(), flush=True)
print("session", os.getsid(0) == os.getpid(), flush=True)
print("cmdline", open("/proc/self/cmdline").read().replace("\\0", " ").strip(), flush=True)
print("preloaded", probe_pre.LOADED_IN != os.getpid(), flush=True)
print("hooked", "probe_hook" in sys.modules, flush=True)
print("main", __name__, flush=True)
sys.stdout.buffer.write(b"bytes \\xff\\n"); sys.stdout.flush()
what = sys.argv[1]
if what == "raise":
    raise RuntimeError("probe failed")
if what == "sleep":
    print("up", flush=True)
    time.sleep(60)
sys.exit(int(what))
"""


@pytest.fixture
def probe(tmp_path):
    """A package ``probe`` (run as ``python -m probe``) that imports ``probe_pre`` at its
    top and whose ``preload.preload`` imports ``probe_hook``; the directory to put on
    PYTHONPATH."""
    pkg = tmp_path / "probe"
    pkg.mkdir()
    (pkg / "__main__.py").write_text(NODE)   # runs at import: the server must never import it
    (pkg / "__init__.py").write_text("")
    (pkg / "preload.py").write_text("def preload(argv):\n    import probe_hook  # noqa: F401\n")
    (tmp_path / "probe_hook.py").write_text("")
    (tmp_path / "probe_pre.py").write_text("import os\nLOADED_IN = os.getpid()\n")
    return tmp_path


def _lines(child, timeout=30):
    deadline = time.monotonic() + timeout
    while child.returncode is None:
        assert time.monotonic() < deadline, f"{child.name}: {list(child.tail)}"
        time.sleep(0.01)
    child.pump.join(timeout)
    return list(child.tail)


def _wait_for(child, text, timeout=30):
    deadline = time.monotonic() + timeout
    while not any(text in line for line in child.tail):
        assert time.monotonic() < deadline, f"{child.name}: {list(child.tail)}"
        time.sleep(0.01)


def test_a_forked_node_is_what_python_m_would_start(probe, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with Supervisor(show=lambda *_: False, env={"PYTHONPATH": str(probe)}) as sup:
        first = sup.start("first", [sys.executable, "-m", "probe", "0"])
        child = sup.start("probe", [sys.executable, "-m", "probe", "3", "x y"],
                          env={"PROBE_VALUE": "seen"})
        assert isinstance(child.proc, forkserver.ForkedProc)
        server = sup._forks.proc.pid
        lines = _lines(child)
    assert child.returncode == 3
    assert "argv ['3', 'x y']" in lines
    assert f"cwd {tmp_path}" in lines
    assert "env seen" in lines
    assert f"ppid {server}" in lines               # the server's child, reaped by it
    assert "session True" in lines
    assert f"cmdline {sys.executable} -m probe 3 x y" in lines
    assert "preloaded True" in lines               # its top imports: imported ahead, in the server
    assert "hooked True" in lines                  # its preload: for the second of its kind...
    assert "hooked False" in _lines(first)         # ...the first loads its own
    assert "main __main__" in lines
    assert "bytes \ufffd" in lines                 # undecodable output replaced, not fatal


def test_exceptions_and_signals_end_a_forked_node_as_they_end_python(probe):
    with Supervisor(show=lambda *_: False, env={"PYTHONPATH": str(probe)}) as sup:
        failing = sup.start("failing", [sys.executable, "-m", "probe", "raise"])
        ok = sup.start("ok", [sys.executable, "-m", "probe", "0"])
        stubborn = sup.start("sleeper", [sys.executable, "-m", "probe", "sleep"])
        assert _lines(ok) and ok.returncode == 0
        lines = _lines(failing)
        assert failing.returncode == 1
        assert any("RuntimeError: probe failed" in line for line in lines)
        _wait_for(stubborn, "up")
        os.kill(stubborn.proc.pid, signal.SIGKILL)
        assert stubborn.proc.wait(timeout=10) == -signal.SIGKILL
        with pytest.raises(subprocess.TimeoutExpired):
            sup.start("later", [sys.executable, "-m", "probe", "sleep"]).proc.wait(timeout=0.05)


def test_stop_ends_the_nodes_and_the_server(probe):
    sup = Supervisor(show=lambda *_: False, env={"PYTHONPATH": str(probe)})
    kids = [sup.start(f"n{i}", [sys.executable, "-m", "probe", "sleep"]) for i in range(3)]
    for child in kids:
        _wait_for(child, "up")
    server = sup._forks.proc
    sup.stop(grace_s=5)
    assert all(child.returncode == -signal.SIGTERM for child in kids)
    assert server.poll() is not None


def test_forked_nodes_die_with_a_killed_launcher(probe, tmp_path):
    pid_file = tmp_path / "pid"
    script = textwrap.dedent(f"""
        import sys, time
        from papf.launch.supervisor import Supervisor
        sup = Supervisor(show=lambda *_: False, env={{"PYTHONPATH": {str(probe)!r}}})
        c = sup.start("sleeper", [sys.executable, "-m", "probe", "sleep"])
        while not c.tail: time.sleep(0.01)
        open({str(pid_file)!r}, "w").write(str(c.proc.pid) + " " + type(c.proc).__name__)
        time.sleep(60)
    """)
    parent = subprocess.Popen([sys.executable, "-c", script], start_new_session=True)
    deadline = time.monotonic() + 30
    while not (pid_file.exists() and pid_file.read_text()) and time.monotonic() < deadline:
        time.sleep(0.05)
    pid, kind = pid_file.read_text().split()
    assert kind == "ForkedProc"
    os.kill(parent.pid, signal.SIGKILL)
    parent.wait()
    deadline = time.monotonic() + 30
    while os.path.exists(f"/proc/{pid}") and time.monotonic() < deadline:
        time.sleep(0.05)   # a zombie of init's goes at once
    assert not os.path.exists(f"/proc/{pid}"), "the node outlived its SIGKILLed launcher"
    # its server went with the launcher (it is the node's parent)


def test_a_node_with_another_interpreter_environment_is_started_by_python_m(probe):
    with Supervisor(show=lambda *_: False, env={"PYTHONPATH": str(probe)}) as sup:
        first = sup.start("first", [sys.executable, "-m", "probe", "0"])
        other = sup.start("other", [sys.executable, "-m", "probe", "5"],
                          env={"PYTHONHASHSEED": "7"})
        assert isinstance(first.proc, forkserver.ForkedProc)
        assert isinstance(other.proc, subprocess.Popen)
        assert "argv ['5']" in _lines(other) and other.returncode == 5
        _lines(first)


def test_the_fork_server_can_be_turned_off(probe, monkeypatch):
    monkeypatch.setenv(forkserver.ENV, "0")
    with Supervisor(show=lambda *_: False, env={"PYTHONPATH": str(probe)}) as sup:
        child = sup.start("probe", [sys.executable, "-m", "probe", "4"])
        assert isinstance(child.proc, subprocess.Popen)
        lines = _lines(child)
    assert child.returncode == 4 and "preloaded False" in lines and sup._forks is None
    assert "hooked False" in lines
    assert "bytes \ufffd" in lines   # the pipe of a process of its own decodes the same way


def test_a_server_that_has_gone_leaves_the_nodes_to_python_m(probe):
    out = __import__("io").StringIO()
    with Supervisor(log_stream=out, show=lambda *_: False, env={"PYTHONPATH": str(probe)}) as sup:
        first = sup.start("first", [sys.executable, "-m", "probe", "0"])
        _lines(first)
        sup._forks.proc.kill()
        sup._forks.proc.wait()
        later = sup.start("later", [sys.executable, "-m", "probe", "6"])
        assert isinstance(later.proc, subprocess.Popen)
        assert _lines(later) and later.returncode == 6
    assert "nodes started without the fork server" in out.getvalue()


def test_a_run_is_the_same_run_with_and_without_the_fork_server(monkeypatch):
    results = []
    for value in ("1", "0"):   # PAPF: its kernels loaded in the server, or in the planner
        monkeypatch.setenv(forkserver.ENV, value)
        code, res, err = papf_run("--world", "energy", "--planner", "papf", "--timeout", "12")
        assert (code, res["outcome"]) == (5, "timeout"), err[-2000:]
        results.append({k: v for k, v in res.items() if k not in ("wall_time_s", "run_id")})
    assert results[0] == results[1]


def test_a_server_that_has_started_a_thread_forks_nothing_more(probe):
    threaded = probe / "threaded"
    threaded.mkdir()
    (threaded / "__init__.py").write_text("")
    (threaded / "__main__.py").write_text("print('threaded node', flush=True)\n")
    (threaded / "preload.py").write_text(
        "import threading, time\n"
        "def preload(argv):\n"
        "    threading.Thread(target=time.sleep, args=(60,), daemon=True).start()\n")
    out = __import__("io").StringIO()
    with Supervisor(log_stream=out, show=lambda *_: False, env={"PYTHONPATH": str(probe)}) as sup:
        first = sup.start("first", [sys.executable, "-m", "threaded"])   # loads its own
        bad = sup.start("threaded", [sys.executable, "-m", "threaded"])  # the server loads it
        later = sup.start("later", [sys.executable, "-m", "probe", "7"])
        assert isinstance(first.proc, forkserver.ForkedProc)
        assert isinstance(bad.proc, subprocess.Popen) and isinstance(later.proc, subprocess.Popen)
        assert "threaded node" in _lines(bad) and bad.returncode == 0
        assert _lines(later) and later.returncode == 7
        _lines(first)
    assert "a fork of it is unsafe" in out.getvalue()


def test_a_request_without_its_output_descriptor_is_refused_and_the_server_goes_on(probe):
    env = {**os.environ, "PYTHONPATH": str(probe)}
    server = forkserver.ForkServer([sys.executable, "-m", "papf.launch.forkserver"], env)
    try:
        server._sock.send(b'{"argv": ["probe", "0"], "env": {}, "cwd": "/"}')   # no fd
        assert "one descriptor" in server._answer()["error"]
        node = server.spawn(["probe", "8"], env)
        assert node.wait(timeout=30) == 8 and "argv ['8']" in node.stdout.read()
    finally:
        server.close()


def test_a_request_with_three_descriptors_gets_its_input_output_and_errors_apart(probe):
    """The tests' warm ``papf`` (tests/support/warm.py) forks with a request's own input,
    output and errors; a node's request keeps one pipe for both and /dev/null for input."""
    (probe / "streams.py").write_text(
        "import sys\nprint('out', sys.stdin.read(), flush=True)\n"
        "print('err', file=sys.stderr, flush=True)\n"
        "print([(s.encoding, s.errors, s.line_buffering, s.write_through) for s in "
        "(sys.stdout, sys.stderr)], file=sys.stderr)\nsys.exit(4)\n")
    env = {**os.environ, "PYTHONPATH": str(probe)}
    server = forkserver.ForkServer([sys.executable, "-m", "papf.launch.forkserver"], env)
    pipes = [os.pipe() for _ in range(3)]
    try:
        os.write(pipes[0][1], b"fed")
        os.close(pipes[0][1])
        node = server.spawn(["streams"], env, cwd=str(probe),
                            streams=(pipes[0][0], pipes[1][1], pipes[2][1]))
        assert node.stdout is None
        for fd in (pipes[0][0], pipes[1][1], pipes[2][1]):
            os.close(fd)
        out, err = (os.fdopen(pipes[k][0]).read() for k in (1, 2))
        plain = subprocess.run([sys.executable, "-m", "streams"], input="fed", env=env,
                               cwd=probe, capture_output=True, text=True, timeout=60)
        assert node.wait(timeout=30) == 4 and out == "out fed\n" and err.startswith("err\n")
        assert (out, err) == (plain.stdout, plain.stderr)   # buffered as python -m's streams
        merged = server.spawn(["streams"], env, cwd=str(probe))
        assert merged.wait(timeout=30) == 4 and merged.stdout.read().startswith("out \nerr\n")
    finally:
        server.close()
