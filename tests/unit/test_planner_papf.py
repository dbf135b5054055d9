"""PAPF (Szczepanski 2022, Sec. III): prediction, top quarks, temporary goal, motion, kernels."""

import dataclasses
import math

import numpy as np
import pytest

from nodes.planner.core import scan_view
from nodes.planner.field import APFParams, Repulsors, apf_force
from nodes.planner.papf.kernels import HAVE_NUMBA, rollout, tail_stagnation
from nodes.planner.papf.params import KernelParams
from nodes.planner.papf.strategy import (
    PAPFParams,
    PAPFStrategy,
    predict,
    quark_force,
    temporary_goal,
)
from nodes.planner.registry import make_planner
from schemas.messages import Goal, Odometry
from tests.support.toysim import box_segments, cast_scan, simulate, toy_world

APF = APFParams()
PP = PAPFParams()
LITERAL = PAPFParams(pull_range_fraction=0.0)   # Algorithm 1 with the far goal's own 5 / r^2 pull
WALL = np.column_stack([np.full(101, 1.0), np.linspace(-1.0, 1.0, 101)])  # across the path at x = 1
NO_POINTS = np.zeros((0, 2))
RING_ANGLES = np.linspace(0.05, 2 * math.pi - 0.05, 300)
RING = 0.6 * np.column_stack([np.cos(RING_ANGLES), np.sin(RING_ANGLES)])  # closed, 8 cm gap ahead


def test_table1_derived_values():
    assert (PP.horizon_m, PP.step_m, PP.max_quarks) == (1.0, 0.03, 10)
    assert PP.i_max == 33 and PP.n_stag == 8                  # lambda/Delta, 0.25 lambda/Delta
    assert PP.stag_radius == pytest.approx(0.0625)            # R = 0.25 * 0.25 * lambda
    assert PP.k_vq_factor * APF.k_vo == pytest.approx(5 * 10 / 300)


def test_free_space_prediction_is_a_straight_line_of_delta_steps():
    p = predict(np.zeros(2), np.array([3.0, 4.0]), NO_POINTS, APF, PP)
    assert p.resolved and not p.reached_goal and len(p.quarks) == 0 and p.abandoned == []
    assert p.path.shape == (34, 2)
    steps = np.diff(p.path, axis=0)
    np.testing.assert_allclose(np.hypot(*steps.T), 0.03, rtol=1e-12)
    np.testing.assert_allclose(p.path[-1], 33 * 0.03 * np.array([0.6, 0.8]), rtol=1e-12)


def test_prediction_stops_at_the_goal():
    p = predict(np.zeros(2), np.array([0.5, 0.0]), NO_POINTS, APF, PP)
    assert p.reached_goal and p.path.shape == (17, 2)          # 16 steps: 0.48 is within Delta
    assert p.path[-1, 0] == pytest.approx(0.48)


def test_tail_stagnation_check():
    still = np.array([[0, 0], [0.01, 0], [0.0, 0.01], [0.01, 0.01]], dtype=float)
    stuck, mean = tail_stagnation(still, 0, 0.0625)
    assert stuck and np.allclose(mean, [0.005, 0.005])
    moving = np.array([[0.03 * k, 0.0] for k in range(8)])
    assert not tail_stagnation(moving, 0, 0.0625)[0]          # spans 0.21 m: > R from the mean
    assert tail_stagnation(moving, 8, 0.0625)[0] is False      # no tail points


def test_head_on_wall_places_a_top_quark_at_the_stagnation_point():
    p = predict(np.zeros(2), np.array([8.0, 0.0]), WALL, APF, LITERAL)
    q0 = p.quarks[0]
    # literal pull (0.089): the prediction stalls where the first wall point enters d_o
    # (0.5 m before the wall)
    assert 1.0 - APF.d_o - 0.03 <= q0[0] <= 1.0 - APF.d_o + 0.03 and abs(q0[1]) < 1e-9
    assert len(p.abandoned) == len(p.quarks) >= 1 and p.resolved
    assert all(a.shape == (34, 2) for a in p.abandoned)
    # the kept path no longer stagnates and keeps off the quark (here, by symmetry, straight back)
    assert np.min(np.hypot(*(p.path - q0).T)) > 0.4


def test_quark_range_d_q_decides_whether_quarks_chain_back_to_the_robot():
    # Goal 8 m away: pull 5 / 7.5^2 = 0.089 at the stall. With d_q = 1 m the quark's force
    # steps by k_VQ / d_q^2 = 0.167 at its range boundary: the next prediction stalls there,
    # d_q before the first quark, and so on (a chain towards the robot). With d_q = 2 m the
    # step is 0.042 < 0.089 and one quark suffices.
    chain = predict(np.zeros(2), np.array([8.0, 0.0]), WALL, APF,
                    PAPFParams(d_q=1.0, pull_range_fraction=0.0))
    assert len(chain.quarks) >= 2
    np.testing.assert_allclose(chain.quarks[1], chain.quarks[0] - [1.0 - 0.01, 0.0], atol=0.03)
    single = predict(np.zeros(2), np.array([8.0, 0.0]), WALL, APF, LITERAL)
    assert len(single.quarks) == 1 and single.resolved


def test_after_m_repetitions_the_prediction_is_unresolved():
    p = predict(np.zeros(2), np.array([3.0, 0.0]), RING, APF, PP)
    assert not p.resolved and len(p.quarks) == PP.max_quarks and len(p.abandoned) == PP.max_quarks


def test_at_most_m_quarks_in_use_a_new_one_replaces_the_oldest():
    old = np.column_stack([np.arange(10.0), np.full(10, 50.0)])  # far beyond d_q: no effect
    p = predict(np.zeros(2), np.array([8.0, 0.0]), WALL, APF, LITERAL, quarks=old)
    assert len(p.quarks) == PP.max_quarks and p.resolved and len(p.abandoned) == 1
    np.testing.assert_array_equal(p.quarks[:-1], old[1:])       # oldest dropped, order kept
    assert 1.0 - APF.d_o - 0.03 <= p.quarks[-1][0] <= 1.0 - APF.d_o + 0.03


def test_pull_range_evaluates_a_far_goal_as_one_lambda_away():
    # goal 8 m: literal pull 5 / 8^2; with the pull range the prediction is pulled as by a
    # goal 1 m away in the same direction (5 / 1^2): the stall moves to where the wall's push
    # reaches 5, i.e. closer to the wall, and only the balance changes (free space: same path)
    lit = predict(np.zeros(2), np.array([8.0, 0.0]), WALL, APF, LITERAL)
    near = predict(np.zeros(2), np.array([8.0, 0.0]), WALL, APF, PP)
    assert lit.quarks[0][0] < near.quarks[0][0] < 1.0 - 0.2
    f_wall = -APF.k_vo * APF.q_v * APF.q_o * np.sum(
        (WALL - near.quarks[0]) / np.hypot(*(WALL - near.quarks[0]).T)[:, None] ** 3
        * (np.hypot(*(WALL - near.quarks[0]).T) <= APF.d_o)[:, None], axis=0)
    assert abs(f_wall[0]) == pytest.approx(APF.k_vg / PP.pull_range ** 2, rel=0.35)
    for goal in ([3.0, 4.0], [0.6, 0.0]):                       # free space, far and near
        a = predict(np.zeros(2), np.array(goal), NO_POINTS, APF, PP)
        b = predict(np.zeros(2), np.array(goal), NO_POINTS, APF, LITERAL)
        np.testing.assert_allclose(a.path, b.path, rtol=0, atol=1e-12)


def test_pull_range_lets_the_prediction_through_a_narrow_gap():
    # a barrier at x = 2 with a 0.5 m gap on the line to a goal 6 m away: the literal far-goal
    # pull (0.14 at the gap) loses to the gap edges' push and the prediction stagnates there;
    # pulled as by a goal lambda away (5) it passes
    ys = np.linspace(-2.0, 2.0, 401)
    barrier = np.column_stack([np.full(ys.size, 2.0), ys])[np.abs(ys) >= 0.25]
    start, goal = np.array([1.2, 0.0]), np.array([6.0, 0.0])
    lit = predict(start, goal, barrier, APF, LITERAL)
    near = predict(start, goal, barrier, APF, PP)
    assert lit.abandoned and np.max(lit.abandoned[0][:, 0]) < 2.0
    assert near.abandoned == [] and near.path[-1, 0] > 2.1 and np.max(np.abs(near.path[:, 1])) < 0.05


def test_quark_force_is_eq7_outside_the_ball_and_linear_inside():
    k = PP.k_vq_factor * APF.k_vo                              # |F| = k / r^2 outside
    q = np.array([[0.45, 0.0]])
    expected = apf_force(np.zeros(2), None, NO_POINTS, APF,
                         extra=(Repulsors(q, PP.k_vq_factor * APF.k_vo, APF.d_o, PP.q_q),))
    np.testing.assert_allclose(quark_force(np.zeros(2), q, APF, PP), expected, rtol=1e-12)
    np.testing.assert_allclose(quark_force(np.zeros(2), q, APF, PP), [-k / 0.45 ** 2, 0.0],
                               rtol=1e-12)
    inside = quark_force(np.zeros(2), np.array([[0.1, 0.0]]), APF, PP)
    np.testing.assert_allclose(inside, [-k * 0.1 / PP.quark_ball_m ** 3, 0.0], rtol=1e-12)
    assert not quark_force(np.zeros(2), np.array([[0.0, 0.0]]), APF, PP).any()   # centre: 0
    # the motion law feels a quark within d_o only (eq. 7's where-clause; the prediction: d_q)
    assert not quark_force(np.zeros(2), np.array([[APF.d_o + 0.01, 0.0]]), APF, PP).any()


def test_temporary_goal_eq8_hand_computed():
    path = np.array([[0, 0], [0.5, 0.2], [1.0, 0.4], [1.2, 0.1]], dtype=float)
    np.testing.assert_array_equal(temporary_goal(np.zeros(2), [1.0, 0.0], path, 1e-3), [1.0, 0.4])
    # slanted line y = x through the robot: A = 1, B = -1, C = 0 -> d = |x - y| / sqrt(2)
    path = np.array([[0, 0], [1, 0], [0.5, 0.5], [2, 1.5]], dtype=float)
    d = np.abs(path[:, 0] - path[:, 1]) / math.sqrt(2)
    expected = path[1:][np.argmax(d[1:])]
    np.testing.assert_array_equal(temporary_goal(np.zeros(2), [2.0, 2.0], path, 1e-3), expected)


def test_temporary_goal_ties_go_to_the_farthest_point_along_the_path():
    path = np.array([[0.03 * k, 0.0] for k in range(34)])
    np.testing.assert_array_equal(temporary_goal(np.zeros(2), [1.0, 0.0], path, 1e-3), path[-1])


def test_motion_force_is_eq7_with_the_temporary_goal():
    s = cast_scan(toy_world(segments=box_segments(1.5, 0.1, 0.4, 0.4)), 0.0, 0.0, 0.0)
    view = scan_view(s, Odometry(stamp_ns=0, x=0.0, y=0.0, yaw=0.0, v=0.0, w=0.0))
    strat = PAPFStrategy()
    plan = strat.plan(np.zeros(2), 0.0, np.array([6.0, 0.0]), view, APF)
    quarks = Repulsors(np.asarray(plan.debug["top_quarks"]).reshape(-1, 2), 5 * APF.k_vo, APF.d_o)
    expected = apf_force(np.zeros(2), plan.temporary_goal, view.points, APF, extra=(quarks,))
    np.testing.assert_allclose(plan.force, expected, rtol=1e-12)
    assert len(plan.predicted_path) == 34 and len(plan.temporary_goal) == 2


def test_unresolved_cycle_drives_by_eq7_with_the_global_goal():
    view = scan_view(cast_scan(toy_world(circles=()), 0.0, 0.0, 0.0),
                     Odometry(stamp_ns=0, x=0.0, y=0.0, yaw=0.0, v=0.0, w=0.0))
    view = type(view)(view.origin, view.angles, view.ranges, RING, view.valid)
    strat, goal = PAPFStrategy(), np.array([3.0, 0.0])
    plan = strat.plan(np.zeros(2), 0.0, goal, view, APF)
    assert plan.mode == "unresolved" and plan.temporary_goal == (3.0, 0.0)
    expected = apf_force(np.zeros(2), goal, RING, APF) + quark_force(np.zeros(2), plan.debug["top_quarks"],
                                                                      APF, PP)
    np.testing.assert_allclose(plan.force, expected, rtol=1e-12)


def test_quarks_persist_and_reset_on_new_goal():
    strat = PAPFStrategy()
    view = scan_view(cast_scan(toy_world(segments=((1.0, -1.0, 1.0, 1.0),)), 0.0, 0.0, 0.0),
                     Odometry(stamp_ns=0, x=0.0, y=0.0, yaw=0.0, v=0.0, w=0.0))
    first = strat.plan(np.zeros(2), 0.0, np.array([8.0, 0.0]), view, APF)
    assert len(first.debug["top_quarks"]) >= 1 and strat.quarks is not None
    again = strat.plan(np.zeros(2), 0.0, np.array([8.0, 0.0]), view, APF)
    np.testing.assert_array_equal(np.asarray(again.debug["top_quarks"])[: len(first.debug["top_quarks"])],
                                  first.debug["top_quarks"])
    strat.reset()
    assert strat.quarks is None


@pytest.mark.skipif(not HAVE_NUMBA, reason="numba not installed")
def test_numba_and_numpy_kernels_are_bit_identical():
    rng = np.random.default_rng(7)
    for dims in (2, 3):
        for _ in range(10):
            obs = rng.uniform(-2.0, 3.0, (300, dims))
            quarks = rng.uniform(-1.0, 2.0, (int(rng.integers(0, 5)), dims))
            goal = rng.uniform(2.0, 6.0, dims)
            for goal_range in (math.inf, 1.0):
                kp = KernelParams(g_goal=-5.0, g_obs=10 / 300, g_q=50 / 300, d_o=0.5, d_q=1.0,
                                  step=0.03, i_max=33, n_stag=8, stag_radius=0.0625, max_quarks=10,
                                  pull_range=goal_range, ball=0.25, tie_tol=1e-3, q_lim=0.5)
                args = (np.zeros(dims), goal, obs, quarks, kp, 41, 0.03)
                a = rollout(*args, use_numba=True)
                b = rollout(*args, use_numba=False)
                assert a[1] == b[1] and np.array_equal(a[0], b[0])
    fast = predict(np.zeros(2), np.array([8.0, 0.0]), WALL, APF, PP)
    slow = predict(np.zeros(2), np.array([8.0, 0.0]), WALL, APF, PAPFParams(use_numba=False))
    assert np.array_equal(fast.path, slow.path) and np.array_equal(fast.quarks, slow.quarks)


def test_planner_state_carries_the_prediction_every_cycle():
    world = toy_world(segments=box_segments(2.0, 0.0, 0.4, 0.4))
    r = simulate(make_planner("papf"), world, goal=(5.0, 0.0), max_time_s=120, keep_states=True)
    driving = [s for s in r.states[:-1]]
    assert all(len(s.predicted_path) >= 2 and len(s.temporary_goal) == 2 for s in driving)
    assert any(s.get("top_quarks") for s in driving) and any(s.get("abandoned_paths") for s in driving)
    assert {s.algorithm for s in r.states} == {"papf"}


def test_head_on_box_papf_reaches_where_apf_stagnates():
    world = toy_world(segments=box_segments(2.0, 0.0, 0.4, 0.4))
    papf = simulate(make_planner("papf"), world, goal=(5.0, 0.0), max_time_s=150)
    apf = simulate(make_planner("apf"), world, goal=(5.0, 0.0), max_time_s=150)
    assert papf.status == "reached" and papf.min_clearance > 0.15
    assert apf.status == "stagnated"


def test_papf_is_deterministic():
    world = toy_world(segments=box_segments(2.0, 0.1, 0.4, 0.4))
    a = simulate(make_planner("papf"), world, goal=(4.0, 0.0), max_time_s=80)
    b = simulate(make_planner("papf"), world, goal=(4.0, 0.0), max_time_s=80)
    assert np.array_equal(a.path, b.path)


def test_same_goal_twice_keeps_quarks_new_goal_resets():
    pl = make_planner("papf")
    pl.set_goal(Goal(stamp_ns=0, x=8.0, y=0.0))
    pl.strategy.quarks = np.array([[1.0, 0.0]])
    pl.set_goal(Goal(stamp_ns=1, x=8.0, y=0.0))
    assert pl.strategy.quarks is not None
    pl.set_goal(Goal(stamp_ns=2, x=7.0, y=0.0))
    assert pl.strategy.quarks is None


@pytest.mark.skipif(not HAVE_NUMBA, reason="numba not installed")
def test_whole_prediction_kernel_matches_the_numpy_loop_bit_for_bit():
    """The one-call numba prediction (rollouts, tail check, quark bookkeeping) and the
    numpy fallback agree bit for bit, in 2-D and 3-D, with and without quarks already placed."""
    rng = np.random.default_rng(11)
    cases = [(np.zeros(2), np.array([3.0, 0.0]), RING, None),
             (np.zeros(2), np.array([8.0, 0.0]), WALL, np.array([[0.4, 0.1], [0.2, -0.3]]))]
    for dims in (2, 3):
        for _ in range(12):
            ang = rng.uniform(0, 2 * math.pi, 200)
            pts = np.column_stack([np.cos(ang), np.sin(ang)] + [rng.uniform(-0.1, 0.1, 200)] * (dims - 2))
            cases.append((rng.uniform(-0.05, 0.05, dims), rng.uniform(2, 4, dims) * np.eye(dims)[0],
                          rng.uniform(0.5, 0.9) * pts, rng.uniform(-0.5, 0.5, (int(rng.integers(0, 12)), dims))))
    for m in (10, 3, 0):
        for pull in (1.0, 0.0):
            fast_pp = PAPFParams(max_quarks=m, pull_range_fraction=pull)
            slow_pp = PAPFParams(max_quarks=m, pull_range_fraction=pull, use_numba=False)
            for pos, goal, obstacles, quarks in cases:
                a = predict(pos, goal, obstacles, APF, fast_pp, quarks)
                b = predict(pos, goal, obstacles, APF, slow_pp, quarks)
                assert (a.resolved, a.reached_goal) == (b.resolved, b.reached_goal)
                assert np.array_equal(a.path, b.path) and np.array_equal(a.quarks, b.quarks)
                assert len(a.abandoned) == len(b.abandoned)
                assert all(np.array_equal(x, y) for x, y in zip(a.abandoned, b.abandoned, strict=True))


@pytest.mark.skipif(not HAVE_NUMBA, reason="numba not installed")
def test_papf_planner_messages_identical_with_and_without_numba():
    """Whole cycles (scan view, prediction, eq. 8, motion law, messages) in both modes."""
    world = toy_world(segments=box_segments(2.0, 0.0, 0.4, 0.4))
    runs = [simulate(make_planner("papf", sets=sets), world, goal=(5.0, 0.0), max_time_s=40,
                     keep_states=True) for sets in ([], ["use_numba=false"])]
    fast, slow = ([dataclasses.replace(s, compute_ns=0).to_bytes() for s in r.states] for r in runs)
    assert fast == slow and np.array_equal(runs[0].path, runs[1].path)
    assert any(s.get("top_quarks") for s in runs[0].states)
