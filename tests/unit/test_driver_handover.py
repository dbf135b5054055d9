"""``python -m nodes.base_driver --driver sim`` runs the world simulator (nodes/world_sim):
the base driver hands over by re-executing, never by importing another node."""

from __future__ import annotations

import subprocess
import sys

import pytest

from nodes.base_driver.__main__ import SIMULATOR, simulator_argv

PY = sys.executable


@pytest.mark.parametrize("argv, rest", [
    (["--driver", "sim", "--world", "open"], ["--world", "open"]),
    (["--seed", "3", "--driver=sim"], ["--seed", "3"]),
    (["--world", "energy"], ["--world", "energy"]),           # sim is the default
    (["--driver", "sim", "--help"], ["--help"]),               # asked for: the simulator's help
])
def test_sim_is_the_simulator_with_the_same_options(argv, rest):
    assert simulator_argv(argv) == [PY, "-m", SIMULATOR, *rest]


@pytest.mark.parametrize("argv", [["--driver", "rosbot"], ["--help"], ["--driver", "robot"],
                                  ["--world", "open", "--driver"]])
def test_the_robot_its_help_and_mistakes_stay_here(argv):
    assert simulator_argv(argv) is None


def _node(*argv: str) -> subprocess.CompletedProcess:
    return subprocess.run([PY, "-m", "nodes.base_driver", *argv], capture_output=True, text=True,
                          timeout=60, stdin=subprocess.DEVNULL)


def test_driver_sim_becomes_the_world_simulator(tmp_path):
    res = _node("--driver", "sim", "--world", str(tmp_path / "none.toml"))
    assert res.returncode == 2 and res.stderr.startswith("world_sim: "), res.stderr
    helped = _node("--driver", "sim", "--help")
    assert helped.returncode == 0 and "python -m nodes.world_sim" in helped.stdout
    assert "<ns>/sim/pose" in helped.stdout


def test_the_drivers_own_help_and_a_mistake_before_the_hand_over():
    helped = _node("--help")
    assert helped.returncode == 0 and "python -m nodes.base_driver" in helped.stdout
    assert "<bridge>/odometry/filtered" in helped.stdout and "--bridge-namespace" in helped.stdout
    res = _node("--watchdg", "1")
    assert res.returncode == 2 and "did you mean --watchdog?" in res.stderr, res.stderr


def test_node_info_names_both_packages_behind_the_drivers_token():
    """``papf node info base_driver``: the simulator's ports and the robot driver's."""
    from papf.bus.graph import node_ports

    variants = node_ports("base_driver").variants
    assert list(variants) == ["--driver sim", "--driver rosbot"]
    assert ("out", "sim/pose", "Odometry") in variants["--driver sim"]
    assert ("out", "link", "LinkHealth") in variants["--driver rosbot"]
    assert list(node_ports("planner").variants)[0] == ""
