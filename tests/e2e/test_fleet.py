"""End to end, fleets: two robots swap the ends of a corridor head-on in one `papf run`
(each LiDAR sees the other robot, both reach, nothing collides, one seed gives one result);
two robots' hosts, each with its own router, joined into one Zenoh network."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys

import pytest
import zenoh

from common.transport import wait_alive, zenoh_config
from papf.launch.supervisor import free_port, wait_port
from schemas import Keys
from tests.support import warm
from tests.support.cli import papf
from tests.support.e2e import papf_run
from tests.support.worlds import STEADY

PY = sys.executable

HEAD_ON = """name = "swap"
description = "two ROSbots head-on in a 2 m corridor"
[[robots]]
name = "r1"
start = [0.0, 0.0, 0.0]
goal = [3.0, 0.0]
[[robots]]
name = "r2"
start = [3.0, 0.0, 3.14159265]
goal = [0.0, 0.0]
[[obstacles]]
kind = "wall"
from = [-1.0, -1.0]
to = [4.0, -1.0]
[[obstacles]]
kind = "wall"
from = [-1.0, 1.0]
to = [4.0, 1.0]
"""


@pytest.mark.slow   # the slow tier (make test-quick leaves it out)
def test_corridor_swap_head_on_both_reach_and_repeat(tmp_path):
    world = tmp_path / "swap.toml"
    world.write_text(HEAD_ON)
    runs = [papf_run("--world", str(world), "--planner", "papf", "--seed", "2", "--timeout", "60",
                     *STEADY) for _ in range(2)]
    for code, res, err in runs:
        assert res is not None, err
        assert (code, res["outcome"], res["collisions"]) == (0, "reached", 0), res
        assert [r["name"] for r in res["robots"]] == ["r1", "r2"]
        assert all(r["outcome"] == "reached" and r["collisions"] == 0 for r in res["robots"])
        assert 0 < res["min_separation_m"] < 1.0   # they passed each other, apart
    first, second = (dict(res, wall_time_s=None, run_id=None) for _, res, _ in runs)
    assert first == second


@pytest.mark.slow   # the slow tier (make test-quick leaves it out)
def test_two_robots_on_two_routers_are_one_network():
    """Two `papf launch robot` hosts, each its own router and namespace, the second joined to
    the first: `papf topic list` on either router sees both robots' nodes; with --namespace
    only that robot's."""
    ports = [free_port(), free_port()]
    ends = [f"tcp/127.0.0.1:{p}" for p in ports]
    hosts = []
    try:
        for i, extra in enumerate(([], ["--join", ends[0]])):
            hosts.append(warm.popen([PY, "-m", "papf", "launch", "robot", "--namespace",
                                     f"fleet{i + 1}", "--listen", ends[i], *extra],
                                    stdout=subprocess.DEVNULL, stderr=subprocess.PIPE))
            assert wait_port(ports[i], 30.0), "a robot's router did not come up"
        with zenoh.open(zenoh_config("client", [ends[1]])) as session:   # the second router
            for ns in ("fleet1", "fleet2"):
                assert not wait_alive(session, Keys(ns), ["base_driver", "lidar_sim"], 60.0)

        def alive(*args):
            out = papf("topic", "list", "--json", "--duration", "0.5", *args, timeout=60)
            return json.loads(out.stdout.strip().splitlines()[-1])

        for end in ends:   # either router sees the whole fleet
            seen = alive("--connect", end)["alive_elsewhere"]
            assert {ns: seen[ns] for ns in ("fleet1", "fleet2")} == {
                "fleet1": ["base_driver", "lidar_sim"], "fleet2": ["base_driver", "lidar_sim"]}
        one = alive("--connect", ends[0], "--namespace", "fleet2")
        assert one == {"alive": ["base_driver", "lidar_sim"]}
    finally:
        for proc in hosts:
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGINT)
        for proc in hosts:
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)
                proc.wait(timeout=30)
