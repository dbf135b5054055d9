"""ORCA as the robot's planner (nodes/planner/orca): registered, settings declared, one RVO2
step toward the goal and around people, a goal reached, a standing group not driven through."""

import dataclasses
import math

import numpy as np
import pytest

from common.errors import ConfigError
from nodes.planner.core import scan_view
from nodes.planner.field import APFParams
from nodes.planner.orca.strategy import ORCAParams, ORCAStrategy
from nodes.planner.registry import PLANNERS, check_setting, make_planner, settings_of, with_role
from nodes.planner.road import Track
from papf.offline.run import simulate as plan_offline
from schemas.messages import Odometry, Scan
from tests.support.toysim import simulate, toy_world
from worlds import load_world


def empty_view(x=0.0, y=0.0):
    scan = Scan(stamp_ns=0, angle_min=0.0, angle_increment=2 * math.pi / 8, range_min=0.1,
                range_max=10.0, ranges=np.full(8, np.inf, np.float32))
    return scan_view(scan, Odometry(stamp_ns=0, x=x, y=y, yaw=0.0, v=0.0, w=0.0))


def test_registered_in_the_crowd_role_and_reads_tracks():
    assert PLANNERS["orca"] is ORCAStrategy and "orca" in with_role("crowd")
    assert ORCAStrategy.uses_objects


def test_every_setting_is_declared_and_its_default_valid():
    names = {f.name for f in dataclasses.fields(ORCAParams)}
    assert names == set(ORCAStrategy.SPECS)
    for name, (table, _, default) in settings_of("orca").items():
        assert check_setting("orca", name, default)[0] == table


@pytest.mark.parametrize("text", ["safety_m=0", "safety_m=nan", "max_neighbors=0",
                                  "time_horizon_s=-1"])
def test_a_value_that_would_switch_avoidance_off_is_refused(text):
    with pytest.raises(ConfigError):
        make_planner("orca", sets=[text])


def test_free_space_heads_for_the_goal_at_v_max():
    s = ORCAStrategy()
    plan = s.plan(np.zeros(2), 0.0, np.array([5.0, 0.0]), empty_view(), APFParams())
    assert plan.heading == pytest.approx(0.0, abs=1e-6)
    assert plan.v_ref == pytest.approx(APFParams().v_max, rel=1e-3)


def test_a_person_walking_head_on_is_avoided_by_turning_aside():
    s = ORCAStrategy()
    s.observe((Track(1.0, 0.0, math.pi, -0.8, 0.0, 0.5, 0.5, 7),), None, 0.0, 0.1)
    plan = s.plan(np.zeros(2), 0.0, np.array([5.0, 0.0]), empty_view(), APFParams())
    assert abs(plan.heading) > 0.05 or plan.v_ref < 0.05   # aside, or waits


def test_reaches_a_goal_among_static_obstacles():
    world = toy_world(circles=[(2.5, 0.15, 0.3)])
    r = simulate(make_planner("orca"), world, max_time_s=150.0)
    assert r.status == "reached" and r.min_clearance > 0.0


def test_a_standing_group_is_passed_not_driven_through():
    r = plan_offline(load_world("crowd-standing"), "orca", seed=0, max_time_s=300.0)
    robot = r.crowd["robots"][0]
    assert robot["outcome"] == "reached" and robot["collisions"] == 0
    assert robot["group_intrusions"] == 0
