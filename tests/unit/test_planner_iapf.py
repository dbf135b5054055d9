"""IAPF (Jin 2024): each mechanism against hand-computed values (nodes/planner/iapf*.py)."""

import dataclasses
import math
from types import SimpleNamespace

import numpy as np
import pytest

from nodes.planner.iapf.algorithm import (
    PAPER_PRESET,
    HostState,
    IAPFCore,
    IAPFParams,
    local_count,
    road_headings,
    scaled,
    stop_deceleration,
    temporary_goal,
)
from nodes.planner.iapf.fields import (
    Lanes,
    Track,
    attraction_gradient,
    gap,
    obstacle_gradient,
    road_gradient,
    safety_distance,
    traditional_gradient,
)

ROAD = Lanes(0.0, 4.0, 2)       # the paper's road: lanes of 4 m, centres at 2 and 6 m
K1, K2 = 3.397, 5.809           # Table 1


@pytest.mark.parametrize(("y", "u", "grad"), [
    (2.0, 0.0, 0.0),              # lane centre: minimum
    (3.0, K2, 2 * K2),            # towards the broken line: k2 delta^2
    (1.0, K1, -4 * K1),           # towards the right solid line: k1 delta^4
    (0.0, 16 * K1, -32 * K1),     # on the solid line (delta = -2)
    (5.0, K2, -2 * K2),           # left lane, towards the broken line
    (7.0, K1, 4 * K1),            # left lane, towards the left solid line
    (3.999, K2 * 1.999 ** 2, 2 * K2 * 1.999),   # just before the ridge: k2 d_w
    (4.0, 4 * K2, -4 * K2),       # the ridge seen from the left lane
    (-1.0, 81 * K1, -108 * K1),   # beyond the solid line the quartic continues
])
def test_road_field_eq5_eq18(y, u, grad):
    got_u, got_g = road_gradient(y, ROAD, K1, K2)
    assert got_u == pytest.approx(u) and got_g == pytest.approx(grad)


def test_road_field_three_lanes_middle_lane_is_all_centre_field():
    road = Lanes(-1.0, 2.0, 3)                       # centres 0, 2, 4
    assert road_gradient(2.5, road, K1, K2) == pytest.approx((K2 * 0.25, K2))
    assert road_gradient(1.5, road, K1, K2) == pytest.approx((K2 * 0.25, -K2))
    assert road_gradient(4.5, road, K1, K2) == pytest.approx((K1 * 0.0625, 4 * K1 * 0.125))


def test_attraction_eqs_6_to_8():
    u, gx, gy = attraction_gradient(10.0, 6.0, 20.0, 0.15, 1.52, 2.0, 8.0)
    # sin(pi * 4 / 8) = 1: the full b3 pulls towards the goal lane; cos = 0
    assert (gx, gy) == pytest.approx((-20.15, 1.52))
    assert u == pytest.approx(-201.5)
    u, gx, gy = attraction_gradient(0.0, 2.0, 20.0, 0.15, 1.52, 2.0, 8.0)
    assert gy == pytest.approx(0.0) and u == pytest.approx(-8 / math.pi * 1.52)
    # the printed half period d_w: one lane away the pull vanishes (sin(pi) = 0)
    assert attraction_gradient(0.0, 6.0, 20.0, 0.15, 1.52, 2.0, 4.0)[2] == pytest.approx(0.0)
    assert attraction_gradient(0.0, 6.0, 20.0, 0.15, 1.52, None, 8.0)[2] == 0.0


def test_safety_distance_eq9_and_gap():
    assert safety_distance(10.0, 5.0, 6.0, 5.0) == pytest.approx(75 / 12 + 5)   # 11.25 m
    assert safety_distance(10.0, 0.0, 6.0, 5.0) == pytest.approx(100 / 12 + 5)
    assert safety_distance(5.0, 10.0, 6.0, 5.0) == pytest.approx(5.0)           # faster: S_m
    ob = Track(20.0, 2.0, 0.0, length=4.5, width=1.8)
    assert gap(10.0, 2.0, 4.5, ob) == pytest.approx(10.0 - 4.5)
    assert gap(18.0, 2.0, 4.5, ob) == 0.0


def test_obstacle_field_straight_behind_hand_computed():
    ob = Track(0.0, 0.0, 0.0)
    u, gx, gy = obstacle_gradient(-3.0, 0.0, ob, 1.0, -0.15, -0.2)
    e = math.exp(-0.15 * 9)                                    # 0.2592
    assert u == pytest.approx(e)
    assert gx == pytest.approx(e * 2 * -0.15 * -3.0)           # +0.2333: the force brakes
    assert gy == pytest.approx(0.0)


def test_obstacle_field_rotates_with_the_heading():
    phi = math.radians(30)
    ob = Track(1.0, 2.0, phi)
    host = (1.0 + 3 * math.cos(phi), 2.0 + 3 * math.sin(phi))   # 3 m ahead along the heading
    u, gx, gy = obstacle_gradient(*host, ob, 1.0, -0.15, -0.2)
    u0, gx0, _ = obstacle_gradient(4.0, 0.0, Track(1.0, 0.0, 0.0), 1.0, -0.15, -0.2)
    assert u == pytest.approx(u0) == pytest.approx(math.exp(-0.15 * 9))
    assert (gx, gy) == pytest.approx((gx0 * math.cos(phi), gx0 * math.sin(phi)))   # rotated too
    # eq. 10 as printed turns the ellipse by -phi: R = (1.5, 2.598), cosine in world axes
    lu, _, _ = obstacle_gradient(*host, ob, 1.0, -0.15, -0.2, literal_rotation=True)
    rx, ry = 3 * math.cos(2 * phi), 3 * math.sin(2 * phi)
    assert lu == pytest.approx(math.cos(phi) * math.exp(-0.15 * rx * rx - 0.2 * ry * ry))


@pytest.mark.parametrize("literal", [False, True])
@pytest.mark.parametrize(("x", "y", "yaw"), [(-5.0, 1.0, 0.0), (3.0, -2.0, 0.4), (-2.0, -3.0, -1.2),
                                             (0.5, 4.0, 2.0)])
def test_obstacle_gradient_is_the_derivative(literal, x, y, yaw):
    ob = Track(0.3, -0.2, yaw)
    h = 1e-6
    _, gx, gy = obstacle_gradient(x, y, ob, 7.0, -0.05, -0.2, literal)
    fx = (obstacle_gradient(x + h, y, ob, 7.0, -0.05, -0.2, literal)[0]
          - obstacle_gradient(x - h, y, ob, 7.0, -0.05, -0.2, literal)[0]) / (2 * h)
    fy = (obstacle_gradient(x, y + h, ob, 7.0, -0.05, -0.2, literal)[0]
          - obstacle_gradient(x, y - h, ob, 7.0, -0.05, -0.2, literal)[0]) / (2 * h)
    assert (gx, gy) == pytest.approx((fx, fy), rel=1e-5, abs=1e-9)


def test_traditional_field_eq12():
    u, gx, gy = traditional_gradient(3.0, 4.0, Track(0.0, 0.0, 0.0), 10.0)
    assert u == pytest.approx(1.0)                      # 0.5 * 10 / 5
    assert (gx, gy) == pytest.approx((-5 * 3 / 125, -5 * 4 / 125))


def test_safety_cut_off_drops_far_obstacles():
    core = IAPFCore(IAPFParams())
    # host at 10 m/s, static car 4.5 m long: D_S = 100/12 + 5 = 13.33 m of gap
    near = Track(4.5 + 13.0 + 0.0, 2.0, 0.0, length=4.5, width=1.8)
    far = Track(4.5 + 13.5, 2.0, 0.0, length=4.5, width=1.8)
    assert core.force(0.0, 2.0, 10.0, [near], ROAD, None, 0.0)[3] == 1
    fx, fy, fox, active = core.force(0.0, 2.0, 10.0, [far], ROAD, None, 0.0)
    assert active == 0 and fox == 0.0 and (fx, fy) == pytest.approx((20.15, 0.0))


def test_local_minimum_count_eq24():
    # left lane (centre 6), nearest solid line 8: the middle line is y = 7
    pts = [(x, 7.5) for x in range(13)] + [(x, 6.2) for x in range(7)]
    assert local_count(pts, 6.3, ROAD) == 13 - 7
    # right lane: oriented towards y = 0, the middle line is 1 (printed sign would be -)
    pts = [(x, 0.5) for x in range(15)] + [(x, 1.5) for x in range(5)]
    assert local_count(pts, 1.8, ROAD) == 10
    assert local_count([(0.0, 1.0)], 1.8, ROAD) == 0


def test_temporary_goal_algorithm1_step4():
    assert temporary_goal(6.5, ROAD) == pytest.approx(2.0)    # trapped left: go right
    assert temporary_goal(1.5, ROAD) == pytest.approx(6.0)


def test_temporary_goal_is_set_and_expires_after_t_c():
    p = dataclasses.replace(IAPFParams(), c_f=5)
    core = IAPFCore(p)
    # an obstacle slightly right of the host in the left lane pushes it to the left line
    ob = Track(12.0, 5.5, 0.0, 5.0, 0.0, 4.5, 1.8)
    s = HostState(0.0, 6.5, 10.0)
    _, info = core.step(s, [ob], ROAD, 1.0)
    assert info.local_count > p.c_f and info.temp_goal_y == pytest.approx(2.0)
    _, info = core.step(HostState(0.0, 6.0, 10.0), [], ROAD, 1.0 + p.t_c - 0.01)
    assert info.temp_goal_y == pytest.approx(2.0)             # still within T_c
    _, info = core.step(HostState(0.0, 6.0, 10.0), [], ROAD, 1.0 + p.t_c + 0.01)
    assert info.temp_goal_y is None


def test_velocity_update_eqs_25_26():
    p = IAPFParams()
    core = IAPFCore(p)
    new, info = core.step(HostState(0.0, 2.0, 8.0), [], ROAD, 0.0)
    assert info.accel == pytest.approx(0.25 * 2.0 ** 3)                 # eta2 (V_c - v)^3 / m
    assert new.v == pytest.approx(8.0 + 2.0 * 0.02)
    ob = Track(10.5, 2.0, 0.0, 8.0, 0.0, 4.5, 1.8)   # gap 6 m < D_S = 17/12 + 5 m
    _, ux, _ = obstacle_gradient(0.0, 2.0, ob, p.obstacle_gain, p.a_x, p.a_y)
    new, info = core.step(HostState(0.0, 2.0, 9.0), [ob], ROAD, 0.0)
    expected = (0.63 * -ux + 0.25 * 1.0) / 1.0
    assert info.f_ox == pytest.approx(-ux) and info.accel == pytest.approx(expected)
    assert new.v == pytest.approx(9.0 + expected * 0.02)
    # braking is limited to a_b (default gain: at most 0.63 * 100 * 0.0858 = 5.4 m/s^2)
    close = Track(7.0, 2.0, 0.0, 0.0, 0.0, 4.5, 1.8)
    strong = IAPFCore(dataclasses.replace(p, obstacle_gain=1000.0))
    _, info = strong.step(HostState(0.0, 2.0, 10.0), [close], ROAD, 0.0)
    assert info.accel == pytest.approx(-p.a_b)


def test_heading_and_position_eqs_21_22():
    core = IAPFCore(dataclasses.replace(IAPFParams(), yaw_rate_max_deg=0.0, heading_max_deg=90.0))
    new, info = core.step(HostState(0.0, 3.0, 10.0), [], ROAD, 0.0)
    fx, fy = 20.15, -2 * K2 * 1.0                              # lane centre field at delta = 1
    assert info.force == pytest.approx((fx, fy))
    phi = math.atan2(fy, fx)
    assert new.yaw == pytest.approx(phi)
    assert (new.x, new.y) == pytest.approx((10.0 * 0.02 * math.cos(phi), 3.0 + 10.0 * 0.02 * math.sin(phi)))


def test_traditional_baseline_keeps_its_speed():
    core = IAPFCore(dataclasses.replace(IAPFParams(), traditional=True))
    new, info = core.step(HostState(0.0, 2.0, 10.0), [Track(8.0, 2.0, 0.0, length=4.5)], ROAD, 0.0)
    assert new.v == 10.0 and info.predicted == [] and info.active == 1


def test_scaled_planner_drives_the_scaled_trajectory():
    p = IAPFParams()
    s, tau = 0.15, 5.0
    q = scaled(p, s, tau)
    assert q.v_cruise == pytest.approx(0.3) and q.step_s == pytest.approx(0.1)
    assert q.k1 == pytest.approx(K1 / s ** 4) and q.eta2 == pytest.approx(0.25 * tau / s ** 2)
    big, small = IAPFCore(p), IAPFCore(q)
    road_s = Lanes(0.0, 4.0 * s, 2)
    a, b = HostState(0.0, 6.0, 10.0), HostState(0.0, 6.0 * s, 10.0 * s / tau)
    ob = Track(25.0, 5.5, 0.0, 6.0, 0.0, 4.5, 1.8)   # not at the 0.5 V_c threshold (rounding)
    for k in range(120):
        obs_a = [ob.moved(k * p.step_s)]
        obs_b = [Track(ob.x * s, ob.y * s, 0.0, ob.vx * s / tau, 0.0, ob.length * s, ob.width * s)
                 .moved(k * q.step_s)]
        a, _ = big.step(a, obs_a, ROAD, k * p.step_s)
        b, _ = small.step(b, obs_b, road_s, k * q.step_s)
        assert (b.x, b.y, b.v) == pytest.approx((a.x * s, a.y * s, a.v * s / tau), rel=1e-6, abs=1e-9)


def test_paper_preset_names_real_settings():
    assert set(PAPER_PRESET) <= {f.name for f in dataclasses.fields(IAPFParams)}
    assert dataclasses.replace(IAPFParams(), **PAPER_PRESET).a_x == -0.15


def test_registry_and_planner_step_with_road_and_tracks():
    from nodes.planner.registry import make_planner
    from schemas.messages import Goal, Odometry, Scan

    planner = make_planner("iapf")
    planner.set_goal(Goal(stamp_ns=0, x=20.0, y=0.15, tolerance=0.2))
    assert planner.road is None
    scan = Scan(stamp_ns=0, angle_min=0.0, angle_increment=0.1, range_min=0.1, range_max=5.0,
                ranges=np.full(8, np.inf, dtype=np.float32))
    odom = Odometry(stamp_ns=0, x=0.0, y=0.15, yaw=0.0, v=0.3, w=0.0)
    cmd, state, _ = planner.step(scan, odom)
    assert cmd.v == 0.0 and state.mode == "no-road"            # no road announced yet
    objects = SimpleNamespace(tracks=[Track(1.0, 0.15, 0.0, 0.1, 0.0, 0.5, 0.3, 7)])
    planner.set_goal(Goal(stamp_ns=0, x=20.0, y=0.15, tolerance=0.2, road_lanes=2,
                          road_y_min=-0.15, road_lane_width=0.6))   # the handshake's road
    assert planner.road == Lanes(-0.15, 0.6, 2)
    cmd, state, _ = planner.step(scan, odom, objects)
    assert state.algorithm == "iapf" and 0.0 < cmd.v <= 0.36
    assert len(state.predicted_path) == IAPFParams().f_step and state.obstacle_count == 1
    # the slow track ahead (0.1 m/s < 0.5 V_c) and a free left lane: a lane change starts;
    # the command is the planned speed along the robot's heading
    assert state.mode == "lane-goal" and state.get("lane_goal_y") == pytest.approx(0.75)
    assert cmd.v == pytest.approx(state.v_target * math.cos(state.heading_ref))


@pytest.mark.parametrize(("traditional", "stop"), [(False, 0.0), (True, 0.0), (False, 0.5)])
def test_prediction_kernel_matches_the_step_by_step_core(traditional, stop):
    from nodes.planner.iapf.kernels import HAVE_NUMBA

    p = dataclasses.replace(IAPFParams(), traditional=traditional, literal_rotation=traditional,
                            stop_decel_frac=stop)
    tracks = [Track(14.0, 5.5, 0.1, 5.0, 0.3, 4.5, 1.8), Track(-6.0, 6.2, 0.0, 9.0, 0.0, 4.5, 1.8)]
    s0 = HostState(0.0, 6.3, 9.5, 0.05)
    s, ref = s0, []
    core = IAPFCore(p)
    for k in range(p.f_step):      # the readable path: iapf_fields through IAPFCore.advance
        s, _ = core.advance(s, tracks, ROAD, 2.0, p.b3, p.predict_step_s, k * p.predict_step_s)
        ref.append((s.x, s.y))
    for use_numba in ([False, True] if HAVE_NUMBA else [False]):
        got = IAPFCore(p, use_numba=use_numba).predict(s0, tracks, ROAD, 2.0)
        np.testing.assert_allclose(got[:, :2], ref, rtol=1e-12, atol=1e-12)


def test_cannot_follow_a_slow_leader_when_the_next_lane_is_free():
    core = IAPFCore(IAPFParams())
    slow = Track(20.0, 2.0, 0.0, 4.0, 0.0, 4.5, 1.8)          # 4 m/s < 0.5 V_c, gap 15.5 m
    # D_S at the cruise speed: (100 - 16) / 12 + 5 = 12 m: 15.5 m is beyond -> follow on
    _, info = core.step(HostState(0.0, 2.0, 10.0), [slow], ROAD, 0.0)
    assert not info.cannot_follow and info.temp_goal_y is None
    _, info = core.step(HostState(5.0, 2.0, 10.0), [slow], ROAD, 0.0)      # gap 10.5 m
    assert info.cannot_follow and info.temp_goal_y == pytest.approx(6.0)
    # a vehicle beside in the left lane: not free, no lane change
    core.reset()
    beside = Track(6.0, 6.0, 0.0, 10.0, 0.0, 4.5, 1.8)
    _, info = core.step(HostState(5.0, 2.0, 10.0), [slow, beside], ROAD, 0.0)
    assert not info.cannot_follow
    # 28.8 km/h (case C's leader) is not slow: follow it
    _, info = core.step(HostState(5.0, 2.0, 10.0), [Track(20.0, 2.0, 0.0, 8.0, 0.0, 4.5, 1.8)],
                        ROAD, 0.0)
    assert not info.cannot_follow


def test_lane_free_ahead_beside_and_behind():
    core = IAPFCore(IAPFParams())
    s = HostState(0.0, 2.0, 10.0)
    assert core.lane_free(6.0, s, [], ROAD)
    assert not core.lane_free(6.0, s, [Track(7.0, 6.0, 0.0, 8.0, 0.0, 4.5, 1.8)], ROAD)    # ahead
    assert core.lane_free(6.0, s, [Track(40.0, 6.0, 0.0, 10.0, 0.0, 4.5, 1.8)], ROAD)      # far
    assert not core.lane_free(6.0, s, [Track(-6.0, 6.0, 0.0, 12.0, 0.0, 4.5, 1.8)], ROAD)  # behind
    assert core.lane_free(6.0, s, [Track(-30.0, 6.0, 0.0, 5.0, 0.0, 4.5, 1.8)], ROAD)


def test_goal_lane_pull_near_the_goal():
    p = IAPFParams()
    core = IAPFCore(p)
    s = HostState(0.0, 6.0, 10.0)
    assert core.lane_goal(s, [], ROAD, 2.0, None) == (2.0, p.b3)            # no goal point
    assert core.lane_goal(s, [], ROAD, 2.0, 100.0) == (2.0, p.b3)           # 100 m > 6 s x V_c
    assert core.lane_goal(s, [], ROAD, 2.0, 50.0) == (2.0, p.b3_temp)
    blocked = [Track(5.0, 2.0, 0.0, 5.0, 0.0, 4.5, 1.8)]
    assert core.lane_goal(s, blocked, ROAD, 2.0, 50.0) == (2.0, p.b3)
    # b3_temp crosses the broken line's ridge k2 d_w unaided: b3_temp sin(pi/4) > k2 d_w
    assert p.b3_temp * math.sin(math.pi / 4) > p.k2 * ROAD.width


def test_brake_priority_suspends_the_return_to_cruise():
    p = dataclasses.replace(IAPFParams(), brake_priority=True)
    ob = Track(10.5, 2.0, 0.0, 0.0, 0.0, 4.5, 1.8)
    _, ux, _ = obstacle_gradient(0.0, 2.0, ob, p.obstacle_gain, p.a_x, p.a_y)
    _, info = IAPFCore(p).step(HostState(0.0, 2.0, 6.0), [ob], ROAD, 0.0)
    assert info.accel == pytest.approx(max(-p.a_b, 0.63 * -ux))      # eta1 F_oX alone
    _, plain = IAPFCore(IAPFParams()).step(HostState(0.0, 2.0, 6.0), [ob], ROAD, 0.0)
    assert plain.accel > 0.0                                        # eq. 25: (V_c - v)^3 wins
    from nodes.planner.iapf.kernels import HAVE_NUMBA
    s0 = HostState(0.0, 2.0, 6.0)
    ref = IAPFCore(p, use_numba=False).predict(s0, [ob], ROAD, 2.0)
    if HAVE_NUMBA:
        np.testing.assert_allclose(IAPFCore(p).predict(s0, [ob], ROAD, 2.0), ref, rtol=1e-12)
    assert ref[-1, 2] < 6.0


def test_stop_law_hand_computed():
    """Host at x = 0 in the left lane at 8 m/s; a car 12 m ahead (centres) at 2 m/s: gap
    12 - 4.5 = 7.5 m, room 7.5 - S_m = 2.5 m, closing 6 m/s -> 6^2 / (2 * 2.5) = 7.2 m/s^2."""
    p = IAPFParams()
    hs = (p.host_length, p.s_m)
    lead = Track(12.0, 6.0, 0.0, 2.0, 0.0, 4.5, 1.8)
    assert stop_deceleration(0.0, 6.0, 8.0, [lead], ROAD, *hs) == pytest.approx(7.2)
    # 0.5 s later the car is 1 m farther: room 3.5 m
    assert stop_deceleration(0.0, 6.0, 8.0, [lead], ROAD, *hs, 0.5) == pytest.approx(36 / 7)
    others = [Track(12.0, 2.0, 0.0, 0.0, 0.0, 4.5, 1.8),      # the other lane
              Track(-12.0, 6.0, 0.0, 0.0, 0.0, 4.5, 1.8),     # behind
              Track(12.0, 6.0, 0.0, 9.0, 0.0, 4.5, 1.8)]      # ahead but faster
    assert stop_deceleration(0.0, 6.0, 8.0, others, ROAD, *hs) == 0.0
    inside = Track(9.0, 6.0, 0.0, 0.0, 0.0, 4.5, 1.8)        # gap 4.5 m < S_m
    assert stop_deceleration(0.0, 6.0, 1.0, [inside], ROAD, *hs) == math.inf
    # in the step: the law takes over above stop_decel_frac a_b = 3 m/s^2, limited to a_b
    on = dataclasses.replace(p, stop_decel_frac=0.5, prediction=False)
    _, info = IAPFCore(on).step(HostState(0.0, 6.0, 8.0), [lead], ROAD, 0.0)
    assert info.accel == pytest.approx(-p.a_b)
    slow = Track(40.0, 6.0, 0.0, 6.0, 0.0, 4.5, 1.8)         # 2^2 / (2 (35.5 - 5)) < 3
    _, a = IAPFCore(on).step(HostState(0.0, 6.0, 8.0), [slow], ROAD, 0.0)
    _, b = IAPFCore(dataclasses.replace(on, stop_decel_frac=0.0)).step(
        HostState(0.0, 6.0, 8.0), [slow], ROAD, 0.0)
    assert a.accel == b.accel


def test_slow_tracks_head_along_the_road():
    tracks = [Track(5.0, 2.0, 1.2, 0.5, 0.5, 4.5, 1.8),      # 0.71 m/s: along the road
              Track(5.0, 2.0, 0.0, 3.0, -3.0, 4.5, 1.8)]     # 4.2 m/s: its direction of travel
    slow, fast = road_headings(tracks, 2.5)
    assert slow.yaw == 0.0 and (slow.x, slow.vx, slow.length) == (5.0, 0.5, 4.5)
    assert fast.yaw == pytest.approx(-math.pi / 4)
    assert road_headings(tracks, 0.0) == tracks
    # the node's scale: 2.5 m/s at car scale is 0.075 m/s on 0.6 m lanes at 0.3 m/s cruise
    assert scaled(IAPFParams(), 0.15, 5.0).heading_min_speed == pytest.approx(0.075)
