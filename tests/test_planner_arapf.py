"""AR-APF (Szczepanski, Energies 2021): detection, virtual wall, side, force, abandonment."""

import math

import numpy as np
import pytest

from nodes.planner.apf import APFParams, Repulsors, apf_force
from nodes.planner.arapf import (
    ARAPFParams,
    ARAPFStrategy,
    detect_minimum,
    object_ends,
    virtual_obstacle,
)
from nodes.planner.core import scan_view
from nodes.planner.registry import make_planner
from nodes.planner.toysim import ToyWorld, box_segments, cast_scan, simulate
from papf.errors import ConfigError
from schemas.messages import Odometry

AP = ARAPFParams()
APF = APFParams()
GOAL = np.array([4.0, 0.0])


def view_of(*segments, x=0.0, y=0.0, yaw=0.0):
    s = cast_scan(ToyWorld(segments=segments), x, y, yaw)
    return scan_view(s, Odometry(stamp_ns=0, x=x, y=y, yaw=yaw, v=0.0, w=0.0))


def test_table1_constants():
    assert AP.k_ro_l / 300 == pytest.approx(5 / 300) and AP.k_virtual_factor == 10
    assert (AP.alpha_deg, AP.d_min, AP.s_min, AP.d_max, AP.n_wall, AP.beta_deg,
            AP.delta_gamma_deg) == (30, 1.2, 0.5, 0.2, 10, 75, 5)


def test_detection_of_a_blocked_sector():
    # wall at 1 m: the +-30 deg beams hit it at 1/cos(30 deg) = 1.155 m < d_min
    assert detect_minimum(view_of((1.0, -1.0, 1.0, 1.0)), GOAL, AP) is not None
    assert detect_minimum(view_of((1.3, -1.0, 1.3, 1.0)), GOAL, AP) is None      # beyond d_min
    assert detect_minimum(view_of((1.0, -1.0, 1.0, 1.0)), np.array([0.8, 0.0]), AP) is None


def test_passage_width_decides():
    wide = view_of((1.0, -1.0, 1.0, -0.4), (1.0, 0.4, 1.0, 1.0))      # 0.8 m >= s_min: a passage
    narrow = view_of((1.0, -1.0, 1.0, -0.15), (1.0, 0.15, 1.0, 1.0))  # 0.3 m < s_min: blocked
    assert detect_minimum(wide, GOAL, AP) is None
    assert detect_minimum(narrow, GOAL, AP) is not None


def test_object_ends_walk_out_to_the_gaps():
    v = view_of((1.0, -0.5, 1.0, 0.7))
    right, left = object_ends(v, *detect_minimum(v, GOAL, AP), GOAL, AP)
    np.testing.assert_allclose(right, [1.0, -0.5], atol=0.03)
    np.testing.assert_allclose(left, [1.0, 0.7], atol=0.03)
    v = view_of((1.0, -0.5, 1.0, 0.5), (1.0, 0.85, 1.0, 1.5))        # 0.35 m gap > d_max
    _, left = object_ends(v, *detect_minimum(v, GOAL, AP), GOAL, AP)
    np.testing.assert_allclose(left, [1.0, 0.5], atol=0.03)
    # a long wall: the walk stops by beta = 75 deg at the latest (y = tan 75 = 3.73), here
    # earlier (y = 2.87, 70.8 deg) where beam spacing on the wall, 0.021 / cos^2, exceeds d_max
    v = view_of((1.0, -5.0, 1.0, 5.0))
    right, left = object_ends(v, *detect_minimum(v, GOAL, AP), GOAL, AP)
    assert 2.5 < left[1] <= math.tan(math.radians(75)) and right[1] == pytest.approx(-left[1])


def test_virtual_obstacle_on_the_side_not_taken_hand_computed():
    right, left = np.array([1.0, -0.5]), np.array([1.0, 0.7])
    # cost right = 1.118 + 3.041 < cost left = 1.221 + 3.081: go right, obstacle on the left
    np.testing.assert_allclose(virtual_obstacle(np.zeros(2), GOAL, right, left, "end"), [1.0, 0.7])
    np.testing.assert_allclose(virtual_obstacle(np.zeros(2), GOAL, right, left, "midpoint"), [0.5, 0.35])
    np.testing.assert_allclose(virtual_obstacle(np.zeros(2), GOAL, right, left, "beside"), [0.0, 0.6])
    mirrored = virtual_obstacle(np.zeros(2), GOAL, np.array([1.0, -0.7]), np.array([1.0, 0.5]),
                                "beside")                        # now left is shorter
    np.testing.assert_allclose(mirrored, [0.0, -0.6])


def test_augmented_force_is_eq4():
    strat = ARAPFStrategy()
    v = view_of((1.0, -0.5, 1.0, 0.7))
    plan = strat.plan(np.zeros(2), 0.0, GOAL, v, APF)
    assert plan.mode == "augmented"
    wall = np.asarray(plan.virtual_walls[0])
    assert wall.shape == (10, 2)
    np.testing.assert_allclose(np.diff(wall, axis=0), np.diff(wall, axis=0)[:1].repeat(9, 0), atol=1e-12)
    field = APFParams(k_vo_l=5.0)
    k = 10 * 5 / 300
    expected = apf_force(np.zeros(2), GOAL, v.points, field,
                         (Repulsors(wall, k, field.d_o), Repulsors(np.asarray(plan.virtual_obstacles), k)))
    np.testing.assert_allclose(plan.force, expected, rtol=1e-12)


def test_abandonment_when_forces_agree():
    strat = ARAPFStrategy()
    strat.plan(np.zeros(2), 0.0, GOAL, view_of((1.0, -0.5, 1.0, 0.7)), APF)
    assert strat.wall is not None
    behind = view_of((1.0, -0.5, 1.0, 0.7), x=2.0)             # past the obstacle
    kept = strat.plan(np.array([0.3, 0.0]), 0.0, GOAL, view_of((1.0, -0.5, 1.0, 0.7), x=0.3), APF)
    assert kept.mode == "augmented" and strat.wall is not None  # still pushed away: keep AR
    plan = strat.plan(np.array([2.0, 0.0]), 0.0, GOAL, behind, APF)
    assert strat.wall is None and plan.mode == "drive" and plan.virtual_walls == []


def test_bad_obstacle_place_is_a_config_error():
    with pytest.raises(ConfigError, match="obstacle_at"):
        make_planner("arapf", sets=["obstacle_at=sky"])


def test_closed_loop_head_on_box_reaches_and_shows_virtual_objects():
    world = ToyWorld(segments=box_segments(2.0, 0.0, 0.4, 0.4))
    r = simulate(make_planner("arapf"), world, goal=(5.0, 0.0), max_time_s=150, keep_states=True)
    assert r.status == "reached" and r.min_clearance > 0.15
    assert any(s.virtual_walls and s.virtual_obstacles for s in r.states)
    assert {s.mode for s in r.states} >= {"drive", "augmented"}
