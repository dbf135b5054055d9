"""papf/offline/crowd.py through the one offline entry point (papf.offline.run.simulate)."""

from __future__ import annotations

import dataclasses

import numpy as np

from papf.offline.run import simulate
from worlds import load_world
from worlds.fleet import PersonSpec, RobotSpec


def _open(**changes):
    return dataclasses.replace(load_world("open"), **changes)


def test_one_robot_of_robots_drives_as_papf_plan_does():
    world = load_world("open")
    alone = simulate(world, "apf", seed=3, max_time_s=20)
    robots = (RobotSpec(name="r1", start=world.start, goal=world.goal, tolerance=0.1),)
    fleet = simulate(_open(robots=robots), "apf", seed=3, max_time_s=20)
    assert fleet.motion == "crowd"
    np.testing.assert_array_equal(fleet.path, alone.path)
    assert fleet.outcome == alone.outcome and fleet.duration_s == alone.duration_s
    assert fleet.crowd["robots"][0]["name"] == "r1"


def test_same_seed_same_figures_and_every_robot_reported():
    a = simulate("crowd-corridor-swap", "papf", seed=1).summary()
    b = simulate("crowd-corridor-swap", "papf", seed=1).summary()
    assert a == b
    assert [r["name"] for r in a["robots"]] == ["r1", "r2"]
    assert a["outcome"] == "reached"
    for r in a["robots"]:
        assert r["collisions"] == 0 and r["min_robot_separation_m"] > 0
        assert r["min_person_separation_m"] is None   # nobody there


def test_a_person_running_into_the_robot_is_a_person_collision():
    # the social-force model has no body: a runner head-on goes through (docs/experiments.md)
    runner = PersonSpec(start=(3.0, 0.0), route=((-3.0, 0.0),), speed=2.5, model="social_force")
    res = simulate(_open(people=(runner,)), "apf", seed=0, max_time_s=20)
    r = res.crowd["robots"][0]
    assert res.outcome == "collision"
    assert (r["collisions_person"], r["collisions_wall"], r["collisions_robot"]) == (1, 0, 0)


def test_people_seen_by_the_lidar_and_kept_clear_of():
    res = simulate("crowd-head-on", "papf", seed=0).summary()
    r = res["robots"][0]
    assert res["outcome"] == "reached" and res["people"] == 1
    assert 0 < r["min_person_separation_m"] < 1.0      # they met
    assert r["intrusions"] >= 1 and r["discomfort_s"] >= 0
