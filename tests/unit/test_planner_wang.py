"""Wang's improved APF (our reading, see nodes/planner/wang/strategy.py and docs/planners.md): 2-D and 3-D."""

import dataclasses
import math

import numpy as np
import pytest

from common.errors import ConfigError
from nodes.planner.core import ScanView
from nodes.planner.field import APFParams
from nodes.planner.registry import load_params, make_planner
from nodes.planner.wang.strategy import (
    WangParams,
    WangStrategy,
    attraction_coef,
    control_point,
    eta,
    lambda_goal,
    lambda_obs,
    wang_force,
)
from tests.support.toysim import simulate, toy_world

WP = WangParams()          # k_att 10, k_rep 5/300, rho_0 0.5 m, rho_1 1 m, R_0 0, offset 0.05 m
S45 = math.sin(math.pi / 4)


def test_params_hand_computed():
    assert WP.rho_1 == 2 * WP.rho_0 == 1.0 and WP.k_rep == pytest.approx(5 / 300)


@pytest.mark.parametrize(("rho_min", "r_0", "expected"), [
    (0.0, 0.0, 0.0),                    # at R_0: sin(-pi/2) -> 0
    (0.125, 0.0, 0.5 * (1 - S45)),      # a quarter of rho_0: sin(pi/4 - pi/2)
    (0.25, 0.0, 0.5),                   # half-way
    (0.375, 0.0, 0.5 * (1 + S45)),
    (0.5, 0.0, 1.0),                    # R_0 + rho_0 and beyond: 1
    (5.0, 0.0, 1.0),
    (0.1, 0.2, 0.0),                    # inside a round obstacle's radius R_0 = 0.2 m
    (0.45, 0.2, 0.5),
    (0.7, 0.2, 1.0),
])
def test_eta_eq6(rho_min, r_0, expected):
    assert eta(rho_min, dataclasses.replace(WP, r_0=r_0)) == pytest.approx(expected, abs=1e-12)


def test_lambda_eq8_hand_computed():
    rho = np.array([0.2, 0.5, 0.625, 0.75, 0.875, 1.0, 2.0])
    np.testing.assert_allclose(lambda_obs(rho, WP),
                               [1.0, 1.0, 0.5 * (1 + S45), 0.5, 0.5 * (1 - S45), 0.0, 0.0], atol=1e-12)
    for d_goal, expected in [(0.0, 0.0), (0.25, 0.5 * (1 - S45)), (0.5, 0.5), (0.75, 0.5 * (1 + S45)),
                             (1.0, 1.0), (3.0, 1.0)]:
        assert lambda_goal(d_goal, WP) == pytest.approx(expected, abs=1e-12)


def test_attraction_coefficient_hands_over_to_the_goal():
    # rho_min = 0.25 m -> eta = 0.5; eta_eff = 1 - lambda_goal * (1 - eta)
    assert attraction_coef(0.25, 5.0, WP) == pytest.approx(0.5)          # far: eta itself
    assert attraction_coef(0.25, 0.5, WP) == pytest.approx(0.75)         # lambda_goal = 0.5
    assert attraction_coef(0.25, 0.0, WP) == pytest.approx(1.0)          # at the target
    assert attraction_coef(2.0, 0.3, WP) == 1.0                          # no obstacle near


def test_attraction_alone_is_linear():
    np.testing.assert_allclose(wang_force([1.0, 1.0], [4.0, 5.0], np.zeros((0, 2)), WP), [30.0, 40.0])


def test_one_obstacle_2d_hand_computed():
    e = 0.5 * (math.sin(0.6 * math.pi - 0.5 * math.pi) + 1)            # eta at rho = 0.3
    rep = WP.k_rep * (1 / 0.3 - 1 / 1.0) / 0.09                          # lambda_obs = lambda_goal = 1
    f = wang_force([0.0, 0.0], [5.0, 0.0], np.array([[0.0, 0.3]]), WP)
    np.testing.assert_allclose(f, [10 * e * 5.0, -rep], rtol=1e-12)


def test_one_obstacle_near_the_goal_hand_computed():
    # goal 0.5 m away (lambda_goal = 0.5), obstacle 0.3 m away (lambda_obs = 1)
    e = 0.5 * (math.sin(0.6 * math.pi - 0.5 * math.pi) + 1)
    rep = 0.5 * WP.k_rep * (1 / 0.3 - 1.0) / 0.09
    f = wang_force([0.0, 0.0], [0.5, 0.0], np.array([[0.0, 0.3]]), WP)
    np.testing.assert_allclose(f, [10 * (1 - 0.5 * (1 - e)) * 0.5, -rep], rtol=1e-12)


def test_one_obstacle_3d_hand_computed_and_taper():
    # obstacle 0.75 m away (between rho_0 and rho_1): lambda_obs = 0.5, eta = 1
    rep = 0.5 * WP.k_rep * (1 / 0.75 - 1.0) / 0.75**2
    f = wang_force(np.zeros(3), [0.0, 0.0, 5.0], np.array([[0.75, 0.0, 0.0]]), WP)
    np.testing.assert_allclose(f, [-rep, 0.0, 50.0], rtol=1e-12)


def test_repulsion_vanishes_at_the_goal():
    goal = np.array([3.0, 0.0])
    obstacle = np.array([[3.25, 0.0], [3.0, 0.25]])
    f = wang_force(goal + [-0.01, -0.01], goal, obstacle, WP)
    assert np.degrees(np.arccos(f @ [1, 1] / np.linalg.norm(f) / math.sqrt(2))) < 10


def test_control_point():
    np.testing.assert_allclose(control_point([1.0, 2.0], math.pi / 2, [5.0, 5.0], WP), [1.0, 2.05])
    # within 2 offsets of the goal the point is at most half-way to it
    np.testing.assert_allclose(control_point([0.0, 0.0], 0.0, [0.06, 0.0], WP), [0.03, 0.0])
    np.testing.assert_allclose(control_point([1.0, 2.0, 3.0], 0.0, [5.0, 5.0, 5.0], WP), [1.0, 2.0, 3.0])
    off = dataclasses.replace(WP, control_offset_m=0.0)
    np.testing.assert_allclose(control_point([1.0, 2.0], 0.3, [5.0, 5.0], off), [1.0, 2.0])


def test_strategy_uses_the_control_point_and_the_scan_size():
    pts = np.array([[1.0, 0.3], [1.2, -0.2]])
    view = ScanView(np.zeros(2), np.zeros(0), np.zeros(0), pts, np.zeros(0, dtype=bool))
    plan = WangStrategy().plan(np.zeros(2), 0.0, np.array([4.0, 0.0]), view, APFParams(lidar_points=150))
    expected = wang_force([0.05, 0.0], [4.0, 0.0], pts, dataclasses.replace(WP, lidar_points=150))
    np.testing.assert_allclose(plan.force, expected, rtol=1e-12)


@pytest.mark.parametrize("setting", ["rho_0=0", "k_att=-1", "control_offset_m=nan", "r_0=-0.1"])
def test_bad_settings_are_refused(setting):
    with pytest.raises(ConfigError, match=setting.split("=")[0]):
        load_params("wang", sets=[setting])


def test_goal_next_to_obstacles_is_reached_2d():
    world = toy_world(circles=((3.35, 0.0, 0.15), (3.0, 0.35, 0.15)))   # surfaces 0.2 m from the goal
    r = simulate(make_planner("wang"), world, goal=(3.0, 0.0), max_time_s=120)
    assert r.status == "reached" and r.min_clearance > 0.1


def test_goal_behind_an_obstacle_on_the_line_2d():
    """Wang Fig. 7-8 in the toy world: goal 0.2 m behind a cylinder standing on the line."""
    world = toy_world(circles=((3.0, 0.0, 0.25),))
    wang = simulate(make_planner("wang"), world, goal=(3.45, 0.0), max_time_s=150)
    assert wang.status == "reached" and wang.min_clearance > 0.15
    # the classic APF and Wang without the control point stop at the saddle in front of it
    assert simulate(make_planner("apf"), world, goal=(3.45, 0.0), max_time_s=150).status == "stagnated"
    fixed = simulate(make_planner("wang", sets=["control_offset_m=0"]), world, goal=(3.45, 0.0),
                     max_time_s=150)
    assert fixed.status == "stagnated"


def test_point_reaches_goal_past_a_sphere_3d():
    rng = np.random.default_rng(3)
    d = rng.normal(size=(400, 3))
    sphere = np.array([0.0, 0.0, 2.5]) + 0.3 * d / np.linalg.norm(d, axis=1)[:, None]
    pos, goal, closest = np.array([0.0, 0.1, 0.0]), np.array([0.0, 0.0, 5.0]), math.inf
    for _ in range(400):
        f = wang_force(pos, goal, sphere, WP)
        pos = pos + 0.03 * f / np.linalg.norm(f)
        closest = min(closest, float(np.min(np.linalg.norm(sphere - pos, axis=1))))
        if np.linalg.norm(goal - pos) <= 0.1:
            break
    assert np.linalg.norm(goal - pos) <= 0.1 and closest > 0.1


def test_unreachable_goal_world_offline():
    """worlds/wang-unreachable-goal (Wang Fig. 7-8): wang reaches it, the classic APF does not."""
    from papf.offline.run import simulate
    from worlds import load_world

    world = load_world("wang-unreachable-goal")
    wang = simulate(world, "wang", seed=0)
    assert wang.outcome == "reached" and wang.collisions == 0 and wang.min_clearance_m > 0.1
    assert simulate(world, "apf", seed=0).outcome in ("stagnated", "failed", "timeout")
