"""One ``--port`` / ``--port-range`` / ``PORT=`` story (papf/launch/portrange.py): the router and every
node inside the range, errors in one line before anything starts, ``make demo`` passes them on."""

from __future__ import annotations

import io
import subprocess

import pytest

from tests.support.cli import papf


def _ports_of(dry_run_json: str) -> list[list[int]]:
    import json
    import re

    procs = json.loads(dry_run_json)["processes"]
    return [[int(p) for a in proc["argv"] for p in re.findall(r"^tcp/[^:]+:(\d+)$", a)]
            for proc in procs]


@pytest.mark.parametrize("command", [["run", "--world", "energy"],
                                     ["launch", "sim", "--world", "energy"]])
def test_port_range_keeps_the_router_and_every_node_inside_it(command):
    from papf.launch.supervisor import free_port

    lo = min(free_port(), 60000)
    res = papf(*command, "--port-range", f"{lo}-{lo + 40}", "--dry-run")
    assert res.returncode == 0, res.stderr
    ports = _ports_of(res.stdout)
    assert all(lo <= p <= lo + 40 for proc in ports for p in proc)
    router = ports[0][0]
    listening = [proc[-1] for proc in ports[1:]]   # each peer node's --listen
    assert len(set(listening)) == len(listening) and router not in listening
    assert all(proc[0] == router for proc in ports[1:])   # every node connects to the router


def test_port_range_errors_are_one_line_before_anything_starts():
    res = papf("run", "--world", "energy", "--port-range", "90-80", "--dry-run")
    assert res.returncode == 2 and "give LO-HI" in res.stderr
    res = papf("run", "--world", "energy", "--port", "7447", "--port-range", "9000-9010")
    assert res.returncode == 2 and "--port 7447 is outside --port-range 9000-9010" in res.stderr
    res = papf("experiment", "energy", "--port", "7600", "--workers", "2", "--out", "x")
    assert res.returncode == 2 and "give --port-range" in res.stderr


def test_launch_port_sets_the_routers_port_on_the_profiles_interface():
    res = papf("launch", "robot", "--port", "7600", "--dry-run")
    assert res.returncode == 0, res.stderr
    assert "tcp/0.0.0.0:7600" in res.stdout and "tcp/127.0.0.1:7600" in res.stdout
    res = papf("launch", "laptop", "--port", "7600", "--world", "energy")
    assert res.returncode == 2 and "runs no router" in res.stderr


def test_experiment_port_puts_every_runs_router_on_it(tmp_path, monkeypatch):
    from rich.console import Console

    from papf.experiments.energy import EnergyExperiment, run_experiment
    from papf.launch.portrange import PORT_ENV
    from tests.support.recordings import FakeRuns

    monkeypatch.setenv(PORT_ENV, "7600")
    fake = FakeRuns()
    run_experiment(EnergyExperiment(out=tmp_path, runs=2, planners=("apf",)),
                   Console(file=io.StringIO()), run_fn=fake)
    assert [c.port for c in fake.configs] == [7600, 7600]


def test_make_demo_takes_port_and_port_range():
    import shutil
    from pathlib import Path

    if shutil.which("make") is None:
        pytest.skip("no make")
    root = Path(__file__).resolve().parents[2]
    res = subprocess.run(["make", "-n", "-C", str(root), "demo", "PORT=7600",
                          "PORT_RANGE=7600-7620", "VENV=.venv"], capture_output=True, text=True,
                         timeout=60)
    assert "papf run --world energy --planner papf --port 7600 --port-range 7600-7620" in res.stdout
