"""``[[robots]]`` and ``[[people]]`` in world files (worlds/fleet.py)."""

from __future__ import annotations

import pytest

from common.errors import WorldError
from worlds import parse_world
from worlds.checks import check_runnable

TWO = {"robots": [{"name": "r1", "start": [0, 0, 0], "goal": [5, 0]},
                  {"name": "r2", "start": [5, 0.5], "goal": [0, 0.5], "planner": "apf",
                   "tolerance": 0.2}]}


def test_robots_give_each_robot_its_start_goal_and_planner():
    w = parse_world(TWO)
    assert [r.name for r in w.fleet] == ["r1", "r2"]
    assert w.fleet[1].start == (5.0, 0.5, 0.0) and w.fleet[1].planner == "apf"
    assert w.fleet[1].tolerance == 0.2 and w.fleet[0].planner is None
    assert (w.start, w.goal) == ((0.0, 0.0, 0.0), (5.0, 0.0))   # the first robot's


def test_a_single_robot_world_is_a_fleet_of_one():
    w = parse_world({"goal": {"position": [3, 1], "tolerance": 0.3}})
    (r,) = w.fleet
    assert (r.name, r.goal, r.tolerance, w.people) == ("", (3.0, 1.0), 0.3, ())


def test_people_walk_to_a_goal_or_along_waypoints():
    w = parse_world({**TWO, "people": [
        {"start": [3, 2], "goal": [3, -2]},
        {"start": [1, 1], "waypoints": [[1, 2], [2, 2]], "loop": True, "speed": 0.6,
         "radius": 0.25, "model": "social_force"}]})
    a, b = w.people
    assert a.route == ((3.0, -2.0),) and (a.speed, a.radius, a.model) == (1.0, 0.3, "orca")
    assert b.route == ((1.0, 2.0), (2.0, 2.0)) and b.loop and b.model == "social_force"


@pytest.mark.parametrize("doc, says", [
    ({"robots": [{"name": "r1", "start": [0, 0], "goal": [1, 0], "plannr": "apf"}]},
     "robots[0].plannr: unknown key; did you mean 'planner'?"),
    ({"robots": [{"name": "a/b", "start": [0, 0], "goal": [1, 0]}]}, "must be a plain key"),
    ({"robots": [{"name": "r", "start": [0, 0], "goal": [1, 0]}] * 2}, "used by another robot"),
    ({"robots": []}, "non-empty array"),
    ({**TWO, "goal": {"position": [1, 0]}}, "remove [robot] and [goal]"),
    ({**TWO, "people": [{"start": [0, 0], "goal": [1, 1], "waypoints": [[1, 2]]}]}, "not both"),
    ({**TWO, "people": [{"start": [0, 0], "goal": [1, 1], "model": "orcaa"}]},
     "not one of orca, social_force"),
    ({**TWO, "people": [{"start": [0, 0], "goal": [1, 1], "speed": 30}]},
     "not a walking speed"),
    ({**TWO, "people": [{"start": [0, 0], "goal": [1, 1], "speed": float("nan")}]},
     "finite number"),
    ({**TWO, "people": [{"start": [0, 0], "goal": [1, 1], "loop": True}]}, "only waypoints"),
    ({**TWO, "people": [{"start": [0, 0], "goal": [1, 1]}] * 201}, "more than 200"),
    ({"robots": [{"name": f"r{i}", "start": [i, 0], "goal": [i, 5]} for i in range(33)]},
     "more than 32"),
    ({**TWO, "peeple": []}, "did you mean 'people'?"),
])
def test_a_bad_fleet_or_crowd_is_refused_in_one_line(doc, says):
    with pytest.raises(WorldError) as err:
        parse_world(doc)
    assert says in str(err.value) and "\n" not in str(err.value)


@pytest.mark.parametrize("doc, says", [
    ({"robots": [{"name": "a", "start": [0, 0], "goal": [3, 0]},
                 {"name": "b", "start": [0.05, 0], "goal": [3, 1]}]},
     "robots 'a' and 'b' start with their footprints overlapping"),
    ({"robots": [{"name": "a", "start": [0, 0], "goal": [3, 0]},
                 {"name": "b", "start": [0, 1], "goal": [3, 1]}],
      "obstacles": [{"kind": "box", "center": [3, 1], "size": [1, 1]}]},
     "robot 'b': the goal (3, 1) lies inside obstacles[0]"),
    ({"goal": {"position": [3, 0]}, "people": [{"start": [0.1, 0], "goal": [3, 0]}]},
     "people[0] starts at (0.1, 0) on the robot's footprint"),
    ({**TWO, "people": [{"start": [2, 2], "goal": [3, 0]}, {"start": [2.3, 2], "goal": [3, 0]}]},
     "people[0] and people[1] start overlapping"),
    ({**TWO, "people": [{"start": [2, 2], "goal": [3, 0]}],
      "obstacles": [{"kind": "cylinder", "center": [2, 2.4], "radius": 0.2}]},
     "people[0] starts at (2, 2) inside obstacles[0] (cylinder)"),
])
def test_a_fleet_or_crowd_that_cannot_start_is_refused(doc, says):
    with pytest.raises(WorldError) as err:
        check_runnable(parse_world(doc))
    assert says in str(err.value) and "\n" not in str(err.value)


def test_robots_side_by_side_and_people_apart_may_start():
    check_runnable(parse_world({**TWO, "people": [{"start": [2, 2], "goal": [3, 0]},
                                                  {"start": [2.7, 2], "goal": [3, 0]}]}))
