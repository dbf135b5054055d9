"""`papf run --link`: the split's process graph, its preflight, the emulated body's contacts
(no process started)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from nodes.base_driver.rosbot import Pose2D
from papf.launch.run import RunConfig
from papf.launch.split import laptop_stall_s, resolve_split
from papf.link.spec import parse_spec
from papf.robot.emulator import BodyContacts
from tests.support.cli import papf
from tests.support.worlds import SHORT, write_world
from worlds import load_world


@pytest.fixture
def world(tmp_path) -> str:
    return str(write_world(tmp_path / "short.toml", SHORT))


def test_the_split_runs_each_side_on_its_own_router_joined_through_the_link(world):
    graph = json.loads(resolve_split(RunConfig(world=world, planner="papf", namespace="ns1",
                                               link="wifi,outage=10@20")))
    by = {(p["host"], p["name"]): p["argv"] for p in graph["processes"]}
    assert set(by) == {("robot", "router"), ("robot", "base_driver"), ("robot", "lidar_sim"),
                       ("robot", "rosbot_emulator"), ("link", "link"), ("laptop", "router"),
                       ("laptop", "energy_meter"), ("laptop", "planner")}
    robot_ep = by[("robot", "router")][by[("robot", "router")].index("--listen") + 1]
    link = by[("link", "link")]
    link_ep = link[link.index("--listen") + 1]
    assert link[link.index("--to") + 1] == robot_ep
    assert by[("laptop", "router")][by[("laptop", "router")].index("--join") + 1] == link_ep
    laptop_ep = by[("laptop", "router")][by[("laptop", "router")].index("--listen") + 1]
    for (host, _), argv in by.items():   # every node talks to its own side's router only
        if "--connect" in argv:
            assert argv[argv.index("--connect") + 1] == (robot_ep if host == "robot" else laptop_ep)
    spec = parse_spec(link[link.index("--spec") + 1])
    assert spec.name == "wifi" and spec.outages == ((10.0, 20.0),)
    assert link[link.index("--t0") + 1] == "signal"    # outages count from the run's start
    assert "wifi" in graph["link"]


def test_the_laptop_waits_out_the_longest_outage_before_it_calls_the_run_stuck():
    assert laptop_stall_s(parse_spec("lan")) == 20.0
    assert laptop_stall_s(parse_spec("lan,outage=10@20")) == 30.0
    assert laptop_stall_s(parse_spec("lan,outage=30@20,outage=5@80")) == 70.0


@pytest.mark.parametrize("args, says", [
    (["--link", "wfi"], "did you mean 'wifi'"),
    (["--link", "delay=nan"], "delay=nan"),
    (["--link", "lan", "--objects", "truth"], "--objects truth is not available"),
    (["--robot-trace", "t.jsonl"], "add --link"),
    (["--link", "lan", "--robot-trace", "/no/such/dir/t.jsonl"], "does not exist"),
])
def test_papf_run_link_refuses_mistakes_with_one_line_before_anything_starts(world, args, says):
    out = papf("run", "--world", world, *args, timeout=60)
    assert out.returncode == 2, out.stderr
    assert says in out.stderr and len(out.stderr.strip().splitlines()) == 1, out.stderr


def test_the_emulated_body_reports_one_contact_per_episode(world):
    contacts = BodyContacts(load_world(world))        # a 0.3 m box at (0.6, 0.6)
    assert contacts.check(Pose2D(0.0, 0.0, 0.0), 0) == []
    assert contacts.check(Pose2D(0.6, 0.42, 0.0), 10_000_000) == ["obstacle 0 (box)"]
    assert contacts.check(Pose2D(0.6, 0.42, 0.0), 30_000_000) == []     # the same episode
    assert contacts.check(Pose2D(0.6, 0.0, 0.0), 50_000_000) == []
    assert contacts.check(Pose2D(0.6, 0.42, 1.0), 400_000_000) == ["obstacle 0 (box)"]


def test_the_body_is_its_footprint_not_its_centre(world):
    contacts = BodyContacts(load_world(world))
    # centre 0.11 m from the box (edge at y = 0.45): the 0.235 m wide body reaches it
    assert contacts.check(Pose2D(0.6, 0.34, 0.0), 0) == ["obstacle 0 (box)"]
    assert BodyContacts(load_world(world)).check(Pose2D(0.6, 0.32, 0.0), 0) == []


def test_the_dry_run_prints_the_graph_without_starting_anything(world, tmp_path):
    out = papf("run", "--world", world, "--link", "lte", "--dry-run", timeout=60, cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["profile"] == "split"
    assert [p.name for p in Path(tmp_path).iterdir()] == ["short.toml"]   # nothing written


def test_the_laptops_recording_names_the_link(world, tmp_path):
    graph = json.loads(resolve_split(RunConfig(world=world, record=str(tmp_path / "r.mcap"),
                                               link="lte,outage=10@20")))
    recorder = next(p["argv"] for p in graph["processes"] if p["name"] == "recorder")
    meta = recorder[recorder.index(next(a for a in recorder if a.startswith("link="))) - 1:]
    assert meta[0] == "--meta" and parse_spec(meta[1].removeprefix("link=")).name == "lte"
