"""People who stand and groups (worlds/fleet.py ``[[groups]]``, common/crowd.py): the format,
the checks before a run, how the crowd moves them, and the planners around them."""

from __future__ import annotations

import numpy as np
import pytest

from common.crowd import Crowd
from common.errors import WorldError
from worlds import load_world, parse_world
from worlds.checks import check_runnable

BASE = {"name": "g", "robot": {"start": [0.0, 0.0, 0.0]}, "goal": {"position": [8.0, 0.0]}}


def world(people, groups=None, **kw):
    doc = {**BASE, "people": people, **kw}
    if groups is not None:
        doc["groups"] = [{"members": g} for g in groups]
    return parse_world(doc)


def test_speed_zero_or_no_route_is_a_standing_person():
    w = world([{"start": [3, 1], "goal": [5, 1], "speed": 0}, {"start": [4, -1]},
               {"start": [2, 2], "goal": [2, -2]}])
    assert [p.standing for p in w.people] == [True, True, False]
    assert w.people[1].route == ()


@pytest.mark.parametrize("model", ["orca", "social_force"])
def test_standing_people_stay_where_they_stand_and_the_others_avoid_them(model):
    w = world([{"start": [3.0, 0.0], "speed": 0.0},
               {"start": [0.0, 0.05], "goal": [6.0, 0.05], "speed": 1.0, "model": model}])
    crowd = Crowd(w.people, w, seed=0)
    least = np.inf
    for _ in range(400):
        crowd.step(0.02, [(-5.0, -5.0, 0.0, 0.0)])
        xy = crowd.positions
        least = min(least, float(np.hypot(*(xy[0] - xy[1]))))
    assert tuple(crowd.positions[0]) == (3.0, 0.0)
    assert crowd.positions[1][0] > 5.0                 # walked past
    if model == "orca":                                # ORCA's discs never overlap
        assert least >= 0.6 - 1e-6


def test_a_walking_group_keeps_together_at_its_slowest_members_pace():
    w = world([{"start": [0.0, 2.0], "goal": [8.0, 2.0], "speed": 1.2},
               {"start": [0.0, 2.8], "goal": [8.0, 2.8], "speed": 0.6}], groups=[[0, 1]])
    crowd = Crowd(w.people, w, seed=0)
    for _ in range(250):                                # 5 s
        crowd.step(0.02, [(0.0, -3.0, 0.0, 0.0)])
    a, b = crowd.positions
    assert abs(a[0] - b[0]) < 0.2 and a[0] == pytest.approx(3.0, abs=0.3)   # 0.6 m/s together


def test_a_group_member_held_back_is_waited_for():
    # the second member starts 2 m behind: the first is pulled back toward the centre
    w = world([{"start": [2.0, 2.0], "goal": [8.0, 2.0], "speed": 0.6},
               {"start": [0.0, 2.6], "goal": [6.0, 2.6], "speed": 0.6}], groups=[[0, 1]])
    crowd = Crowd(w.people, w, seed=0)
    for _ in range(150):
        crowd.step(0.02, [(0.0, -3.0, 0.0, 0.0)])
    a, b = crowd.positions
    assert a[0] - b[0] < 1.8


@pytest.mark.parametrize("people, groups, says", [
    ([{"start": [3, 1]}], [[0]], "must be 2 to 12 indexes"),
    ([{"start": [3, 1]}, {"start": [4, 1]}], [[0, 2]], "2 is not a person"),
    ([{"start": [3, 1]}, {"start": [4, 1]}, {"start": [5, 1]}], [[0, 1], [1, 2]],
     "already in groups[0]"),
    ([{"start": [3, 1]}, {"start": [4, 1], "goal": [4, 3]}], [[0, 1]], "all stand or all walk"),
    ([{"start": [3, 1], "goal": [3, 3]}, {"start": [4, 1], "waypoints": [[4, 3], [4, 1]]}],
     [[0, 1]], "as many points"),
    ([{"start": [3, 1]}, {"start": [4, 1]}], [[0, True]], "indexes"),
])
def test_a_bad_group_is_refused_in_one_line(people, groups, says):
    with pytest.raises(WorldError) as err:
        world(people, groups)
    assert says in str(err.value) and "\n" not in str(err.value)


def test_a_group_with_a_misspelt_key_is_refused():
    with pytest.raises(WorldError, match=r"groups\[0\]\.member: unknown key; did you mean "
                                         "'members'"):
        parse_world({**BASE, "people": [{"start": [3, 1]}, {"start": [4, 1]}],
                     "groups": [{"member": [0, 1]}]})


def test_a_person_standing_on_the_goal_is_refused_before_the_run():
    with pytest.raises(WorldError, match="stands at .* on the robot's goal"):
        check_runnable(world([{"start": [8.0, 0.1]}]))
    check_runnable(world([{"start": [8.0, 0.1], "goal": [8.0, 3.0]}]))   # walks away: fine


def test_the_packaged_standing_world_has_a_standing_group_and_a_standing_person():
    w = load_world("crowd-standing")
    assert all(p.standing for p in w.people) and w.groups[0].members == (0, 1, 2)
    check_runnable(w)


@pytest.mark.parametrize("planner", ["papf", "arapf"])
def test_nobody_drives_through_the_standing_group(planner):
    from papf.offline.run import simulate

    r = simulate(load_world("crowd-standing"), planner, seed=0, max_time_s=300.0)
    robot = r.crowd["robots"][0]
    assert robot["outcome"] == "reached" and robot["collisions"] == 0
    assert robot["group_intrusions"] == 0 and robot["group_s"] == 0.0
