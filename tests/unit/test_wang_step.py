"""Wang as published (papf/offline/wang_step.py): the traditional baseline's force by hand, the
fixed-step point robot on the paper's map scale, what it refuses."""


import numpy as np
import pytest

from common.errors import ConfigError
from nodes.planner.wang.strategy import WangAPFParams, traditional_force
from papf.offline.run import simulate
from papf.offline.wang_step import PointParams, fixed_step
from worlds import parse_world


def _world(obstacles, goal=(10.0, 0.0)):
    return parse_world({"name": "t", "description": "t", "robot": {"start": [0, 0, 0]},
                        "goal": {"position": list(goal), "tolerance": 0.25},
                        "obstacles": [{"kind": "cylinder", "center": list(c), "radius": r}
                                      for c, r in obstacles]})


def test_traditional_force_is_eqs_2_and_4_by_hand():
    table1 = WangAPFParams(k_att=10.0, k_rep_l=2.0, lidar_points=1, rho_0=20.0)   # the fixed step's
    f = traditional_force(np.zeros(2), np.array([3.0, 4.0]), np.array([[0.0, -0.5]]), table1)
    rep = 2.0 * (1 / 0.5 - 1 / 20.0) / 0.25            # K_rep (1/rho - 1/rho_0) / rho^2, away
    np.testing.assert_allclose(f, [30.0, 40.0 + rep])
    wp = WangAPFParams(lidar_points=1)
    g = traditional_force(np.zeros(2), [1.0, 0.0], np.array([[0.0, 0.25], [0.0, 0.6]]), wp)
    np.testing.assert_allclose(g, [10.0, -2.0 * (4.0 - 2.0) / 0.0625])   # 0.6 m: beyond rho_0


def test_fixed_step_walks_half_units_and_reaches_a_free_target():
    r = fixed_step(_world([((5.0, 3.0), 0.2)]), "traditional")
    assert r.outcome == "reached" and r.cycles == 20 and r.motion == "fixed-step"
    np.testing.assert_allclose(np.linalg.norm(np.diff(r.path, axis=0), axis=1), 0.5)


def test_fixed_step_collides_with_an_obstacle_on_the_line_and_fails_after_j():
    r = fixed_step(_world([((5.0, 0.0), 0.3)]), "traditional")
    assert r.outcome == "collision" and r.min_clearance_m < 0 and r.collisions == 1
    stuck = fixed_step(_world([], goal=(10.0, 0.0)), "traditional", PointParams(iterations=5))
    assert stuck.outcome == "failed" and stuck.cycles == 5


def test_fixed_step_results_are_in_metres_with_the_map_scale():
    """3-D worlds are stored 0.1 to metres: the walk's 0.5-unit steps are 0.05 m of path."""
    r = simulate("wang-3d-fig9", "wang", motion="fixed-step")
    assert r.units_per_m == 10.0 and r.planner == "wang" and r.outcome == "reached"
    np.testing.assert_allclose(np.linalg.norm(np.diff(r.path, axis=0), axis=1), 0.05)
    assert r.summary()["cycles"] == r.cycles == r.path.shape[0] - 1


def test_fixed_step_takes_only_wangs_planners_and_no_settings():
    with pytest.raises(ConfigError, match="valid"):
        simulate(_world([]), "apf", motion="fixed-step")
    with pytest.raises(ConfigError, match="do not apply"):
        simulate(_world([]), "wang", params=["preset=paper"], motion="fixed-step")
    with pytest.raises(ConfigError, match="motion"):
        simulate(_world([]), "wang", motion="teleport")


def test_fixed_step_refuses_boxes_and_unknown_methods():
    with pytest.raises(ConfigError, match="round obstacles"):
        fixed_step("papf-test-1", "traditional")
    with pytest.raises(ConfigError, match="valid"):
        fixed_step(_world([]), "magic")
