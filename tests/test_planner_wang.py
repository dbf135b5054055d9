"""Wang's improved APF (our reconstruction, see nodes/planner/wang.py): 2-D and 3-D."""

import math

import numpy as np
import pytest

from nodes.planner.registry import make_planner
from nodes.planner.toysim import ToyWorld, simulate
from nodes.planner.wang import WangParams, eta, lambda_goal, lambda_obs, wang_force

WP = WangParams()


def test_coefficients_hand_computed():
    assert WP.rho_1 == 2 * WP.rho_0 == 1.0 and WP.k_rep == pytest.approx(5 / 300)
    assert eta(0.0, WP) == pytest.approx(0.0) and eta(WP.rho_0 / 2, WP) == pytest.approx(0.5)
    assert eta(WP.rho_0, WP) == 1.0 and eta(5.0, WP) == 1.0
    np.testing.assert_allclose(lambda_obs(np.array([0.2, 0.75, 1.0, 2.0]), WP), [1.0, 0.5, 0.0, 0.0],
                               atol=1e-12)
    assert lambda_goal(0.0, WP) == 0.0 and lambda_goal(0.5, WP) == pytest.approx(0.5)
    assert lambda_goal(3.0, WP) == 1.0


def test_attraction_alone_is_linear():
    np.testing.assert_allclose(wang_force([1.0, 1.0], [4.0, 5.0], np.zeros((0, 2)), WP), [30.0, 40.0])


def test_one_obstacle_2d_hand_computed():
    e = 0.5 * (math.sin(0.6 * math.pi - 0.5 * math.pi) + 1)            # eta at rho = 0.3
    rep = WP.k_rep * (1 / 0.3 - 1 / 1.0) / 0.09                          # lambda_obs = lambda_goal = 1
    f = wang_force([0.0, 0.0], [5.0, 0.0], np.array([[0.0, 0.3]]), WP)
    np.testing.assert_allclose(f, [10 * e * 5.0, -rep], rtol=1e-12)


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


def test_goal_next_to_obstacles_is_reached_2d():
    world = ToyWorld(circles=((3.35, 0.0, 0.15), (3.0, 0.35, 0.15)))   # surfaces 0.2 m from the goal
    r = simulate(make_planner("wang"), world, goal=(3.0, 0.0), max_time_s=120)
    assert r.status == "reached" and r.min_clearance > 0.1


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
