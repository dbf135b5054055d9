"""AR-APF (Szczepanski, Energies 2021): detection, virtual wall, side, obstacle, abandonment."""

import math

import numpy as np
import pytest

from common.errors import ConfigError
from nodes.planner.arapf.strategy import (
    ARAPFParams,
    ARAPFStrategy,
    abandon,
    angle_deg,
    choose_left,
    detect_minimum,
    object_ends,
    obstacle_beside,
    opening,
    wall_points,
    with_wall,
)
from nodes.planner.core import scan_view
from nodes.planner.field import APFParams, Repulsors, apf_force
from nodes.planner.registry import make_planner
from papf.offline.run import simulate as plan_offline
from schemas.messages import Odometry
from tests.support.toysim import box_segments, cast_scan, simulate, toy_world

AP = ARAPFParams()
APF = APFParams()
GOAL = np.array([4.0, 0.0])
K_VIRTUAL = 10 * 5 / 300            # k_RW = k_RD = 10 k_RO, k_RO = 5 / L, L = 300


def view_of(*segments, x=0.0, y=0.0, yaw=0.0):
    s = cast_scan(toy_world(segments=segments), x, y, yaw)
    return scan_view(s, Odometry(stamp_ns=0, x=x, y=y, yaw=yaw, v=0.0, w=0.0))


def test_table1_constants():
    assert AP.k_ro_l / 300 == pytest.approx(5 / 300) and AP.k_virtual_factor == 10
    assert (AP.alpha_deg, AP.d_min, AP.s_min, AP.d_max, AP.n_wall, AP.beta_deg,
            AP.delta_gamma_deg) == (30, 1.2, 0.5, 0.2, 10, 75, 5)
    assert AP.obstacle_offset_m == AP.s_min / 2


# -- Sec. 3.1 detection --------------------------------------------------------------
def test_opening_is_the_chord_at_the_nearer_bound():
    assert opening(1.0, 1.2, math.radians(60)) == pytest.approx(1.0)        # 2 * 1.0 * sin 30
    assert opening(1.2, 0.5, math.radians(20)) == pytest.approx(2 * 0.5 * math.sin(math.radians(10)))


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


def test_a_sliver_beside_a_near_end_is_no_passage():
    # wall x = 0.5 up to y = 0.2 (21.8 deg); free beams 21.8..30 deg. Opening at the end
    # (0.54 m): 2 * 0.54 * sin(4.1 deg) = 0.08 m < s_min. The bound-to-bound distance
    # (0.5, 0.2) -> (1.2 cos 30, 1.2 sin 30) = 0.67 m would call it a passage.
    v = view_of((0.5, -1.0, 0.5, 0.2))
    assert detect_minimum(v, GOAL, AP) is not None
    assert detect_minimum(v, GOAL, ARAPFParams(passage_width="gap")) is None


# -- Sec. 3.2 virtual wall -----------------------------------------------------------
def test_object_ends_stop_at_a_gap_wider_than_d_max():
    v = view_of((1.0, -0.5, 1.0, 0.7))
    right, left = object_ends(v, *detect_minimum(v, GOAL, AP), GOAL, AP)
    np.testing.assert_allclose(right, [1.0, -0.5], atol=0.03)     # beam spacing ~0.03 m there
    np.testing.assert_allclose(left, [1.0, 0.7], atol=0.03)
    v = view_of((1.0, -0.5, 1.0, 0.5), (1.0, 0.85, 1.0, 1.5))     # beams through the gap: stop
    _, left = object_ends(v, *detect_minimum(v, GOAL, AP), GOAL, AP)
    np.testing.assert_allclose(left, [1.0, 0.5], atol=0.03)
    # a step back behind the end at y = 0.5 (26.6 deg); the next beam (27.8 deg) hits x = 1.1
    # at y = 0.58: 0.13 m from (1, 0.5) < d_max, the walk goes on to (1.1, 1.0) ...
    v = view_of((1.0, -0.5, 1.0, 0.5), (1.1, 0.45, 1.1, 1.0))
    _, left = object_ends(v, *detect_minimum(v, GOAL, AP), GOAL, AP)
    np.testing.assert_allclose(left, [1.1, 1.0], atol=0.03)
    # ... at x = 1.3 it hits y = 0.69: 0.35 m > d_max, the object ends at (1, 0.5)
    v = view_of((1.0, -0.5, 1.0, 0.5), (1.3, 0.45, 1.3, 1.0))
    _, left = object_ends(v, *detect_minimum(v, GOAL, AP), GOAL, AP)
    np.testing.assert_allclose(left, [1.0, 0.5], atol=0.03)


def test_object_ends_stop_at_beta():
    # a long wall: the walk stops by beta = 75 deg at the latest (y = tan 75 = 3.73), here
    # earlier (y = 2.87, 70.8 deg) where beam spacing on the wall, 0.021 / cos^2, exceeds d_max
    v = view_of((1.0, -5.0, 1.0, 5.0))
    right, left = object_ends(v, *detect_minimum(v, GOAL, AP), GOAL, AP)
    assert 2.5 < left[1] <= math.tan(math.radians(75)) and right[1] == pytest.approx(-left[1])
    narrow = ARAPFParams(beta_deg=45.0)                           # tan 45 = 1.0 m
    right, left = object_ends(v, *detect_minimum(v, GOAL, narrow), GOAL, narrow)
    assert 0.95 < left[1] <= 1.0 and -1.0 <= right[1] < -0.95


def test_wall_has_n_wall_points_evenly_from_end_to_end():
    wall = wall_points(np.array([1.0, -0.5]), np.array([1.0, 0.7]), 10)
    assert wall.shape == (10, 2)
    np.testing.assert_allclose(wall[:, 0], 1.0)
    np.testing.assert_allclose(np.diff(wall[:, 1]), 1.2 / 9)
    np.testing.assert_allclose(wall[[0, -1]], [[1.0, -0.5], [1.0, 0.7]])


def test_perception_with_the_wall_ray_casts_the_segment():
    v = view_of((0.6, 0.3, 0.6, 0.5))                             # a real stub nearer than the wall
    seen, virtual = with_wall(v, np.array([1.0, -1.0]), np.array([1.0, 1.0]))
    i0 = int(np.argmin(np.abs(v.angles)))                         # beam at 0 deg
    i30 = int(np.argmin(np.abs(v.angles - math.radians(-30))))
    i60 = int(np.argmin(np.abs(v.angles - math.radians(60))))
    assert seen.ranges[i0] == pytest.approx(1.0 / math.cos(v.angles[i0])) and virtual[i0]
    assert seen.ranges[i30] == pytest.approx(1.0 / math.cos(v.angles[i30])) and virtual[i30]
    assert not virtual[i60] and math.isinf(seen.ranges[i60])     # 60 deg passes the wall's end
    i35 = int(np.argmin(np.abs(v.angles - math.radians(35))))   # the stub at 0.6 m wins
    assert not virtual[i35] and seen.ranges[i35] == pytest.approx(v.ranges[i35])


# -- Sec. 3.3 side and virtual obstacle ----------------------------------------------
def test_shorter_side_hand_computed():
    right, left = np.array([1.0, -0.5]), np.array([1.0, 0.7])
    # right: 1.1180 + 3.0414 = 4.1594 m < left: 1.2207 + 3.0806 = 4.3013 m
    assert choose_left(np.zeros(2), GOAL, right, left) is False
    assert choose_left(np.zeros(2), GOAL, np.array([1.0, -0.7]), np.array([1.0, 0.5])) is True
    assert choose_left(np.zeros(2), GOAL, np.array([1.0, -0.6]), np.array([1.0, 0.6])) is True  # tie


def test_virtual_obstacle_beside_the_robot_on_the_side_not_taken():
    np.testing.assert_allclose(obstacle_beside(np.zeros(2), GOAL, True, 0.25), [0.0, -0.25])
    np.testing.assert_allclose(obstacle_beside(np.zeros(2), GOAL, False, 0.25), [0.0, 0.25])
    # oblique goal: u = (0.6, 0.8), right normal (0.8, -0.6)
    np.testing.assert_allclose(obstacle_beside(np.array([1.0, 1.0]), np.array([4.0, 5.0]), True, 0.25),
                               [1.2, 0.85])


def test_new_ar_places_wall_side_and_obstacle():
    strat = ARAPFStrategy()
    v = view_of((1.0, -0.5, 1.0, 0.7))                            # right end is nearer: go right
    plan = strat.plan(np.zeros(2), 0.0, GOAL, v, APF)
    assert plan.mode == "augmented" and strat.go_left is False
    wall = np.asarray(plan.debug["virtual_walls"][0])
    assert wall.shape == (10, 2)
    np.testing.assert_allclose(wall[[0, -1]], [[1.0, -0.5], [1.0, 0.7]], atol=0.03)
    np.testing.assert_allclose(plan.debug["virtual_obstacles"], [[0.0, 0.25]])   # on the left, s_min / 2
    field = APFParams(k_vo_l=5.0)
    expected = apf_force(np.zeros(2), GOAL, v.points, field,
                         (Repulsors(wall, K_VIRTUAL, field.d_o), Repulsors(plan.debug["virtual_obstacles"], K_VIRTUAL)))
    np.testing.assert_allclose(plan.force, expected, rtol=1e-12)      # eq. 4


# -- Sec. 3.4 abandonment ------------------------------------------------------------
def test_abandonment_threshold_delta_gamma():
    f_goal = np.array([1.0, 0.0])
    at = lambda deg: np.array([math.cos(math.radians(deg)), math.sin(math.radians(deg))])  # noqa: E731
    assert angle_deg(at(30.0), f_goal) == pytest.approx(30.0)
    assert abandon(at(4.9), f_goal, 5.0) and abandon(2 * at(-4.9), f_goal, 5.0)
    assert not abandon(at(5.1), f_goal, 5.0) and not abandon(np.zeros(2), f_goal, 5.0)


@pytest.mark.parametrize(("obstacle_y", "kept"), [(-1.0, True), (-3.0, False)])
def test_abandonment_in_the_strategy_hand_computed(obstacle_y, kept):
    # free space, goal 4 m: F_goal = 5 / 16 = 0.3125 along x; obstacle below pushes up with
    # k_RD / d^2: d = 1 m -> 0.1667, atan(0.1667 / 0.3125) = 28.1 deg > 5: AR kept;
    # d = 3 m -> 0.0185, atan = 3.4 deg <= 5: AR abandoned (wall far behind, out of d_o)
    strat = ARAPFStrategy()
    strat.wall = wall_points(np.array([-5.0, -0.6]), np.array([-5.0, 0.6]), 10)
    strat.obstacle = np.array([[0.0, obstacle_y]])
    plan = strat.plan(np.zeros(2), 0.0, GOAL, view_of(), APF)
    assert (strat.wall is not None) is kept
    assert plan.mode == ("augmented" if kept else "drive")
    expected = 28.07 if kept else 0.0
    assert angle_deg(plan.force, np.array([1.0, 0.0])) == pytest.approx(expected, abs=0.01)


def test_bad_passage_width_is_a_config_error():
    with pytest.raises(ConfigError, match="passage_width"):
        make_planner("arapf", sets=["passage_width=sky"])


# -- closed loop (toy world: ideal unicycle, exact scans) ------------------------------
def test_without_a_local_minimum_arapf_is_apf_with_its_k_ro():
    world = toy_world(segments=box_segments(3.0, 0.5, 0.4, 0.4))   # box 0.3 m beside the line
    ar = simulate(make_planner("arapf"), world, goal=(6.0, 0.0), max_time_s=120, keep_states=True)
    apf = simulate(make_planner("apf", sets=["k_vo_l=5"]), world, goal=(6.0, 0.0), max_time_s=120)
    assert ar.status == apf.status == "reached"
    assert {s.mode for s in ar.states[:-1]} == {"drive"}          # the last one is the stop
    np.testing.assert_array_equal(ar.path, apf.path)


U_TRAP = ((2.8, -0.6, 2.8, 0.6), (2.0, -0.6, 2.8, -0.6), (2.0, 0.6, 2.8, 0.6))


@pytest.mark.parametrize("segments", [U_TRAP, ((2.0, -0.6, 2.0, 0.6),)], ids=["u_trap", "wall"])
def test_closed_loop_bypasses_a_dead_end_and_abandons_ar(segments):
    world = toy_world(segments=segments)
    r = simulate(make_planner("arapf"), world, goal=(5.0, 0.0), max_time_s=150, keep_states=True)
    assert r.status == "reached" and r.min_clearance > 0.3
    modes = [s.mode for s in r.states]
    first = modes.index("augmented")
    assert "drive" in modes[first:]                               # abandoned before the goal
    aug = [s for s in r.states if s.mode == "augmented"]
    assert all(len(s.get("virtual_walls")[0]) == 10 and len(s.get("virtual_obstacles")) == 1 for s in aug)
    obstacles = {s.get("virtual_obstacles")[0] for s in aug}
    assert len(obstacles) > 1                                     # kept beside the robot ...
    assert aug[-1].get("virtual_obstacles") == aug[-2].get("virtual_obstacles")  # ... then left in place


# -- the paper's tests (offline: pybullet LiDAR, ROSbot command limits, footprint collisions)
@pytest.mark.parametrize("world", ["arapf-test-1", "arapf-test-2", "arapf-test-3"])
def test_paper_worlds_are_bypassed_offline(world):
    r = plan_offline(world, "arapf", keep_states=True)
    assert r.outcome == "reached" and r.collisions == 0
    assert any(s.mode == "augmented" for s in r.states)
