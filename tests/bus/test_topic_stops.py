"""Issue #35: every topic tool that would run until Ctrl-C stops alike on ``--once``,
``--count N`` and ``--duration S`` (``papf topic echo … --duration 3`` as the README says)."""

from __future__ import annotations

import subprocess
import sys
import threading
import time

import pytest

from schemas import Keys, Twist
from tests.bus.test_bus_tools import _publish_for

KEYS = Keys("rosbot")
CMD = [sys.executable, "-m", "papf", "topic"]


def _topic(*args, router: str) -> subprocess.CompletedProcess:
    return subprocess.run([*CMD, *args, "--connect", router], capture_output=True, text=True,
                          timeout=90, stdin=subprocess.DEVNULL)


@pytest.fixture
def scans(router, session):
    stop = threading.Event()
    th = _publish_for(session, 300.0, stop)   # 20 Hz until stopped
    yield router
    stop.set()
    th.join()


def test_echo_duration_prints_what_came_and_stops(scans):
    t0 = time.monotonic()
    r = _topic("echo", "scan", "--duration", "3", router=scans)
    assert r.returncode == 0, r.stderr
    assert r.stdout.count("# rosbot/scan") >= 5           # 20 Hz for 3 s, under any load
    assert time.monotonic() - t0 < 60


def test_echo_duration_with_nothing_published_is_exit_5(router):
    r = _topic("echo", "nothing/here", "--duration", "1", router=router)
    assert r.returncode == 5 and "no message on nothing/here within 1 s" in r.stderr


def test_hz_takes_count_and_once(scans):
    r = _topic("hz", "scan", "--count", "5", router=scans)
    assert r.returncode == 0 and "rosbot/scan" in r.stdout and " Hz (" in r.stdout
    r = _topic("hz", "scan", "--once", router=scans)
    assert r.returncode == 0 and r.stdout.count("rosbot/scan") == 1


def test_pub_takes_count_and_duration(router, session):
    got: list[Twist] = []
    sub = session.declare_subscriber(KEYS.cmd_vel,
                                     lambda s: got.append(Twist.from_bytes(s.payload.to_bytes())))
    try:
        r = _topic("pub", "cmd_vel", "{v: 0.1, w: 0.0}", "--count", "3", "--rate", "20", router=router)
        assert r.returncode == 0, r.stderr
        deadline = time.monotonic() + 10
        while len(got) < 3 and time.monotonic() < deadline:
            time.sleep(0.05)
        assert len(got) == 3 and got[-1].v == pytest.approx(0.1)
        got.clear()
        r = _topic("pub", "cmd_vel", "{v: 0.2, w: 0.0}", "--duration", "1", "--rate", "10", router=router)
        assert r.returncode == 0, r.stderr
        assert 1 <= len(got) <= 11
    finally:
        sub.undeclare()


@pytest.mark.parametrize("tool", [["echo", "scan"], ["hz", "scan"], ["pub", "cmd_vel", "{}"]])
def test_every_tool_has_the_three_stops(tool):
    for flag in ("--once", "--count", "--duration"):
        r = subprocess.run([*CMD, *tool, "--help"], capture_output=True, text=True, timeout=60)
        assert flag in r.stdout, (tool, flag)


def test_topic_list_on_a_narrow_terminal_keeps_every_cell_whole(scans, session):
    """Issue #35, tables that fit: `papf topic list` on a terminal is a table that fits it."""
    import io

    from rich.console import Console

    from papf.bus.topics import topic_list
    from papf.console.tables import print_table

    out = io.StringIO()
    console = Console(file=out, force_terminal=True, width=60, color_system=None)
    topic_list(session, KEYS, 1.0, lambda line: out.write(line + "\n"),
               table=lambda t: print_table(t, console))
    text = out.getvalue()
    assert all(len(line) <= 60 for line in text.splitlines())
    assert "KEY: rosbot/scan" in text and "TYPE:     papf/Scan/v1" in text
