"""Shared fixtures: a real Zenoh router process on a free port, node processes that
always die with the test, and a client session for the test itself."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile

import pytest
import zenoh

from common.transport import zenoh_config
from papf.launch.supervisor import Supervisor, free_port, wait_port
from tests.support import warm
from tests.support.cli import interrupt

# pytest caches the test modules it rewrote for its asserts only where bytecode may be written;
# where PYTHONDONTWRITEBYTECODE is set (this machine sets it) every worker of every run parsed
# and rewrote all the test files again: half of a worker's collection (docs/performance.md
# "The test suite's time"). Allowed here, in pytest's own process only: the processes the
# tests start keep the environment's setting.
sys.dont_write_bytecode = False


def pytest_configure(config):
    """The launchers' run keys and namespace locks (common.runauth, papf.launch.claim) of this
    test run go to a directory of its own: never the user's, never another test run's (two
    suites at once each launch in the namespace ``rosbot``)."""
    config.papf_runtime = tempfile.mkdtemp(prefix="papf-tests-")
    os.environ["XDG_RUNTIME_DIR"] = config.papf_runtime


def pytest_unconfigure(config):
    shutil.rmtree(getattr(config, "papf_runtime", ""), ignore_errors=True)


@pytest.fixture
def router(tmp_path_factory):
    """Start `python -m papf.launch.router` on a free loopback port (forked from the test
    worker's warm interpreter, tests/support/warm.py); yield its endpoint."""
    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    log = tmp_path_factory.mktemp("router") / "router.log"
    with log.open("w") as err:
        proc = warm.popen([sys.executable, "-m", "papf.launch.router", "--listen", endpoint],
                          stdout=subprocess.DEVNULL, stderr=err)
    try:
        assert wait_port(port, 15.0), f"router did not start: {log.read_text()[-2000:]}"
        yield endpoint
    finally:
        interrupt(proc, 10)


@pytest.fixture
def spawn():
    """``spawn(name, [python -m ...])`` — processes are killed (group) at test end."""
    sup = Supervisor(show=lambda name, line: True)
    yield sup.start
    sup.stop()


@pytest.fixture
def session(router):
    """A Zenoh client session of the test, connected to the router fixture."""
    with zenoh.open(zenoh_config("client", [router])) as s:
        yield s


def tiny_disk_free(path) -> int:
    return shutil.disk_usage(path).free


@pytest.fixture
def tiny_disk(tmp_path):
    """A 256 KB tmpfs mounted at ``tmp_path/disk`` (a disk that fills up); skipped where
    mounting is not allowed (not root, no tmpfs)."""
    disk = tmp_path / "disk"
    disk.mkdir()
    if os.geteuid() != 0 or subprocess.run(["mount", "-t", "tmpfs", "-o", "size=256k", "tmpfs",
                                            str(disk)], capture_output=True).returncode != 0:
        pytest.skip("cannot mount a tmpfs here (needs root)")
    try:
        yield disk
    finally:
        subprocess.run(["umount", "-l", str(disk)], capture_output=True)


TIERS = ("unit", "bus", "e2e")


def pytest_collection_modifyitems(items):
    """Markers follow the folders: a test in ``tests/<tier>/`` carries the marker ``<tier>``."""
    for item in items:
        tier = item.path.parent.name
        if tier in TIERS:
            item.add_marker(getattr(pytest.mark, tier))
