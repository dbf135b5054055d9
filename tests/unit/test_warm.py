"""The tests' warm ``papf`` (tests/support/warm.py): a command forked from the worker's warm
interpreter answers as ``python -m papf`` does — exit code, output and errors apart, working
directory — and a timeout ends it as ``subprocess.run``'s does."""

import os
import subprocess
import sys

import pytest

from papf.launch.supervisor import free_port
from tests.support import warm

PAPF = [sys.executable, "-m", "papf"]


@pytest.mark.parametrize("args", [["run", "--world", "nowhere"], ["plan", "--world", "open",
                                                                  "--planner", "apf", "--json"]])
def test_a_forked_command_answers_as_python_m_does(args):
    forked = warm.popen([*PAPF, *args])
    assert isinstance(forked, warm.Proc)           # from the server, not a new interpreter
    out, err = forked.communicate(timeout=120)
    plain = subprocess.run([*PAPF, *args], capture_output=True, text=True, timeout=120,
                           stdin=subprocess.DEVNULL)
    assert (forked.returncode, out, err) == (plain.returncode, plain.stdout, plain.stderr)


def test_a_forked_command_runs_in_the_callers_directory(tmp_path):
    (tmp_path / "w.toml").write_text("[goal]\nposition = [1]\n")
    r = warm.run([*PAPF, "run", "--world", "w.toml"], cwd=tmp_path)
    assert r.returncode == 2 and "goal.position" in r.stderr, r.stderr


def _link() -> list[str]:
    """A link emulator: runs until stopped."""
    return [*PAPF, "link", "--listen", f"tcp/127.0.0.1:{free_port()}",
            "--to", f"tcp/127.0.0.1:{free_port()}"]


def test_a_timeout_ends_the_command_and_its_group():
    proc = warm.popen(_link())
    with pytest.raises(subprocess.TimeoutExpired):
        proc.communicate(timeout=2)
    assert proc.poll() is None                        # as Popen's: still running
    with pytest.raises(subprocess.TimeoutExpired):
        warm.run(_link(), timeout=2)                  # as subprocess.run's: killed
    proc.kill()
    assert proc.wait(timeout=30) == -9


def test_fork_off_runs_python_m(monkeypatch):
    monkeypatch.setenv(warm.ENV, "0")
    monkeypatch.setattr(warm, "_server", None)
    proc = warm.popen([*PAPF, "--version"])
    assert isinstance(proc, subprocess.Popen)
    out, _ = proc.communicate(timeout=60)
    assert proc.returncode == 0 and out.startswith("papf-stack")
    assert os.environ[warm.ENV] == "0"


def test_a_server_first_needed_in_another_directory_still_forks(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)                       # the server itself starts in the checkout
    monkeypatch.setattr(warm, "_server", None)
    proc = warm.popen([*PAPF, "--version"])
    assert isinstance(proc, warm.Proc)
    out, _ = proc.communicate(timeout=60)
    assert proc.returncode == 0 and out.startswith("papf-stack")
