"""A pytest plugin for ``papf bench suite``: each test's CPU seconds and wall time.

CPU is the test process's own plus every child process it reaped (``RUSAGE_SELF`` +
``RUSAGE_CHILDREN``), and the worker's warm ``papf`` server's with the commands it forked for
the tests and reaped, so a test that runs the stack is charged with the stack's processes.
Each worker (pytest-xdist) writes ``$PAPF_CPU_PER_TEST.<worker>.tsv``: ``cpu_s wall_s tier
nodeid``, the tier ``slow`` for a test with that marker, else its folder (unit, bus, e2e).
A measurement, never a judgement: nothing here fails a test.
"""

from __future__ import annotations

import os
import resource
import sys
import time

import pytest

_rows: list[tuple[str, str, float, float]] = []


def _cpu_s() -> float:
    own = resource.getrusage(resource.RUSAGE_SELF)
    reaped = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + reaped.ru_utime + reaped.ru_stime + _warm_cpu_s()


def _warm_cpu_s() -> float:
    """The worker's warm ``papf`` server (tests/support/warm.py), with the commands it forked
    and reaped: its processes are its children, not the worker's, until it exits."""
    warm = sys.modules.get("tests.support.warm")
    server = getattr(warm, "_server", None)
    if server is None:
        return 0.0
    try:
        with open(f"/proc/{server.proc.pid}/stat", "rb") as f:
            fields = f.read().rsplit(b")", 1)[1].split()
    except OSError:   # it has exited: the worker reaped it, its time is in RUSAGE_CHILDREN
        return 0.0
    return sum(int(x) for x in fields[11:15]) / os.sysconf("SC_CLK_TCK")   # utime..cstime


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item, nextitem):
    cpu0, wall0 = _cpu_s(), time.monotonic()
    yield
    tier = "slow" if item.get_closest_marker("slow") else item.nodeid.split("/")[1]
    _rows.append((tier, item.nodeid, _cpu_s() - cpu0, time.monotonic() - wall0))


def pytest_sessionfinish(session):
    out = os.environ.get("PAPF_CPU_PER_TEST")
    if not out or not _rows:
        return
    worker = os.environ.get("PYTEST_XDIST_WORKER", "main")
    with open(f"{out}.{worker}.tsv", "w") as fh:
        fh.writelines(f"{cpu:.3f}\t{wall:.3f}\t{tier}\t{nodeid}\n" for tier, nodeid, cpu, wall in _rows)
