"""Supervisor: staged stop order, and no orphans even when the supervisor is SIGKILLed."""

import os
import signal
import subprocess
import sys
import textwrap
import time

from papf.launch.supervisor import Supervisor

SLEEPER = [sys.executable, "-c",
           "import signal, sys, time\n"
           "signal.signal(signal.SIGTERM, lambda *_: (print('term', time.monotonic(), flush=True), sys.exit(0)))\n"
           "print('up', flush=True)\n"
           "time.sleep(60)"]


def wait_lines(child, n, timeout=30):
    deadline = time.monotonic() + timeout
    while len(child.tail) < n:
        assert time.monotonic() < deadline, f"{child.name}: {list(child.tail)}"
        time.sleep(0.01)


def alive(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    with open(f"/proc/{pid}/stat") as f:  # a zombie is not alive
        return f.read().split(")")[-1].split()[0] != "Z"


def test_staged_stop_stops_named_children_last():
    sup = Supervisor(show=lambda *_: False)
    kids = {name: sup.start(name, SLEEPER) for name in ("a", "recorder", "router")}
    for c in kids.values():
        wait_lines(c, 1)
    sup.stop(last=("recorder", "router"))
    for c in kids.values():
        wait_lines(c, 2)
    t = {n: float(c.tail[-1].split()[1]) for n, c in kids.items()}
    assert t["a"] < t["recorder"] < t["router"]
    assert all(c.returncode == 0 for c in kids.values())


def test_children_die_with_a_killed_supervisor(tmp_path):
    pid_file = tmp_path / "pid"
    script = textwrap.dedent(f"""
        import sys, time
        from papf.launch.supervisor import Supervisor
        sup = Supervisor(show=lambda *_: False)
        c = sup.start("sleeper", {SLEEPER!r})
        open({str(pid_file)!r}, "w").write(str(c.proc.pid))
        time.sleep(60)
    """)
    parent = subprocess.Popen([sys.executable, "-c", script], start_new_session=True)
    deadline = time.monotonic() + 20
    while not (pid_file.exists() and pid_file.read_text()) and time.monotonic() < deadline:
        time.sleep(0.05)
    child_pid = int(pid_file.read_text())
    assert alive(child_pid)
    os.kill(parent.pid, signal.SIGKILL)
    parent.wait()
    deadline = time.monotonic() + 30
    while alive(child_pid) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not alive(child_pid), "the child outlived its SIGKILLed supervisor"


def test_stop_returns_after_every_childs_last_line_is_printed():
    import io

    out = io.StringIO()
    burst = [sys.executable, "-c",
             "import signal, sys, time\n"
             "def bye(*_):\n"
             "    for i in range(150): print('last', i, flush=True)\n"
             "    sys.exit(0)\n"
             "signal.signal(signal.SIGTERM, bye)\n"
             "print('up', flush=True)\n"
             "time.sleep(60)"]
    def slow_show(name, line):   # a log stream slower than the children: the pipe holds the rest
        time.sleep(0.001)
        return True
    sup = Supervisor(log_stream=out, show=slow_show)
    kids = [sup.start(name, burst) for name in ("a", "b")]
    for c in kids:
        wait_lines(c, 1)
    sup.stop()
    text = out.getvalue()
    for name in ("a", "b"):   # the lines written just before exiting, all of them, already
        assert f"[{name}] last 149" in text and text.count(f"[{name}] last ") == 150
