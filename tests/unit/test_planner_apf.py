"""Classic APF core (PAPF paper eqs. 2-5) and the planner core around it."""

import dataclasses
import math

import numpy as np
import pytest

from common.errors import ConfigError
from nodes.planner.apf.strategy import APFStrategy
from nodes.planner.core import Planner, scan_view
from nodes.planner.field import (
    APFParams,
    Repulsors,
    apf_force,
    coulomb_sum,
    heading_ref,
    speed_ref,
    turn_rate,
)
from nodes.planner.registry import load_params, make_planner
from schemas.messages import Goal, Odometry, Scan
from tests.support.toysim import simulate, toy_world

P = APFParams()


def odom(x=0.0, y=0.0, yaw=0.0, t=0):
    return Odometry(stamp_ns=t, x=x, y=y, yaw=yaw, v=0.0, w=0.0)


def scan(ranges, t=0, inc=None, **kw):
    ranges = np.asarray(ranges, dtype=np.float32)
    inc = inc if inc is not None else 2 * math.pi / len(ranges)
    return Scan(stamp_ns=t, angle_min=kw.pop("angle_min", 0.0), angle_increment=inc,
                range_min=0.2, range_max=10.0, ranges=ranges, **kw)


# -- eq. 2 ----------------------------------------------------------------------
def test_table1_defaults():
    assert P.k_vg == 5 and P.q_v == P.q_o == -1 and P.q_g == 1 and P.lidar_points == 300
    assert P.k_vo == pytest.approx(10 / 300) and P.theta_err_max == pytest.approx(math.radians(30))


def test_goal_attraction_hand_computed():
    # r = (3, 4), |r| = 5: F = -k q_V q_G / 25 * r/5 = +5/25 * (0.6, 0.8)
    f = apf_force([0.0, 0.0], [3.0, 4.0], np.zeros((0, 2)), P)
    np.testing.assert_allclose(f, [0.12, 0.16], rtol=1e-12)


def test_one_obstacle_repels_and_far_point_is_ignored():
    obstacles = np.array([[0.5, 0.0], [0.0, P.d_o + 0.01]])  # the second is beyond d_o
    f = apf_force([0.0, 0.0], None, obstacles, P)
    np.testing.assert_allclose(f, [-P.k_vo / 0.25, 0.0], rtol=1e-12)


def test_goal_plus_obstacle_sum():
    f = apf_force([1.0, 1.0], [1.0, 3.0], np.array([[1.5, 1.0]]), P)
    np.testing.assert_allclose(f, [-P.k_vo / 0.25, 5.0 / 4.0], rtol=1e-12)


def test_three_d_case():
    # goal at (1, 2, 2): |r| = 3; obstacle at (0, 0, -0.5) pushes +z with k_VO / 0.25
    f = apf_force(np.zeros(3), [1.0, 2.0, 2.0], np.array([[0.0, 0.0, -0.5]]), P)
    expected = 5.0 / 9.0 * np.array([1, 2, 2]) / 3.0 + np.array([0, 0, P.k_vo / 0.25])
    np.testing.assert_allclose(f, expected, rtol=1e-12)


def test_extra_repulsors_have_their_own_constant_and_range():
    quark = Repulsors(np.array([[0.0, -0.5]]), k=5 * P.k_vo, d_max=1.0)
    far = Repulsors(np.array([[0.0, 2.0]]), k=100.0, d_max=1.0)
    f = apf_force([0.0, 0.0], None, np.zeros((0, 2)), P, extra=(quark, far))
    np.testing.assert_allclose(f, [0.0, 5 * P.k_vo / 0.25], rtol=1e-12)


def test_coincident_point_exerts_no_force():
    assert np.all(coulomb_sum(np.zeros(2), np.zeros((1, 2))) == 0.0)
    assert np.all(apf_force([1.0, 1.0], [1.0, 1.0], np.zeros((0, 2)), P) == 0.0)


# -- eqs. 3-5 and the heading controller ------------------------------------------
def test_heading_ref_all_quadrants():
    assert heading_ref([-1.0, -1.0]) == pytest.approx(-3 * math.pi / 4)
    assert heading_ref([0.0, 2.0]) == pytest.approx(math.pi / 2)


@pytest.mark.parametrize("deg, alpha", [(0, 1.0), (15, 0.5), (-15, 0.5), (30, 0.0), (45, 0.0)])
def test_eq5_speed_law(deg, alpha):
    assert speed_ref(0.05, math.radians(deg), P) == pytest.approx(alpha * 0.05)
    assert speed_ref(10.0, math.radians(deg), P) == pytest.approx(min(alpha * 10.0, P.v_max))


def test_turn_rate_wraps_and_saturates():
    assert turn_rate(0.1, 0.0, P) == pytest.approx(P.k_theta * 0.1)
    assert turn_rate(math.pi - 0.1, -math.pi + 0.1, P) == pytest.approx(-P.k_theta * 0.2)
    assert turn_rate(3.0, 0.0, P) == P.w_max


# -- scan -> world points ---------------------------------------------------------
def test_scan_points_use_pose_and_sensor_offset_and_drop_invalid():
    s = scan([1.0, np.nan, np.inf, 0.1, 11.0, 2.0], inc=math.pi / 2,
             sensor_x=0.1, sensor_y=0.0, sensor_yaw=math.pi / 2)
    v = scan_view(s, odom(1.0, 2.0, math.pi / 2))
    # sensor at (1, 2.1) facing -x (yaw pi/2 + pi/2): beam 0 -> (0, 2.1); beam 5 (angle 5pi/2) -> +y
    np.testing.assert_allclose(v.origin, [1.0, 2.1], atol=1e-12)
    np.testing.assert_allclose(v.points, [[0.0, 2.1], [1.0, 0.1]], atol=1e-6)
    assert v.valid.tolist() == [True, False, False, False, False, True]
    assert np.isinf(v.ranges[1:5]).all()


# -- planner status -----------------------------------------------------------------
def test_no_goal_is_idle_and_stopped():
    pl = Planner(APFStrategy())
    cmd, state, status = pl.step(scan([np.inf] * 8, t=5), odom(t=5))
    assert (cmd.v, cmd.w, cmd.stamp_ns) == (0.0, 0.0, 5) and status.state == "idle"
    assert state.algorithm == "apf" and state.stamp_ns == 5


def test_ready_then_drive_then_reached_sticks():
    pl = Planner(APFStrategy())
    st = pl.set_goal(Goal(stamp_ns=3, x=1.0, y=0.0, tolerance=0.1))
    assert (st.state, st.stamp_ns) == ("ready", 3)
    cmd, state, status = pl.step(scan([np.inf] * 8, t=100), odom(t=100))
    assert status.state == "driving" and cmd.v == pytest.approx(P.v_max) and cmd.w == 0.0
    assert state.force[0] == pytest.approx(5.0)
    cmd, _, status = pl.step(scan([np.inf] * 8, t=200), odom(0.95, t=200))
    assert status.state == "reached" and cmd.v == cmd.w == 0.0
    _, _, status = pl.step(scan([np.inf] * 8, t=300), odom(0.5, t=300))
    assert status.state == "reached"
    pl.set_goal(Goal(stamp_ns=4, x=1.0, y=0.0, tolerance=0.1))   # same goal: no reset
    assert pl.step(scan([np.inf] * 8, t=400), odom(0.5, t=400))[2].state == "reached"


def test_stagnation_after_window_without_progress():
    pl = Planner(APFStrategy(), APFParams(stagnation_window_s=2.0, stagnation_progress_m=0.1))
    pl.set_goal(Goal(stamp_ns=0, x=5.0, y=0.0))
    states = [pl.step(scan([np.inf] * 8, t=k * 10**8), odom(0.004 * k, t=k * 10**8))[2]
              for k in range(25)]
    assert states[20].state == "driving" and states[21].state == "stagnated"
    cmd, _, st = pl.step(scan([np.inf] * 8, t=26 * 10**8), odom(0.0, t=26 * 10**8))
    assert st.state == "stagnated" and cmd.v == cmd.w == 0.0 and "no progress" in st.reason


def test_a_strategy_that_is_still_searching_restarts_the_window_up_to_the_hard_cap():
    class Searching(APFStrategy):                # e.g. PAPF placing a new top quark every cycle
        def plan(self, *args):
            return dataclasses.replace(super().plan(*args), searching=True)

    pl = Planner(Searching(), APFParams(stagnation_window_s=2.0, stagnation_max_s=4.0))
    pl.set_goal(Goal(stamp_ns=0, x=5.0, y=0.0))
    states = [pl.step(scan([np.inf] * 8, t=k * 10**8), odom(0.0, t=k * 10**8))[2].state
              for k in range(45)]
    assert states[30] == "driving"               # past the 2 s window: the search goes on
    assert states[40] == "driving" and states[41] == "stagnated"   # 4 s cap without progress


def test_params_file_and_set_overrides(tmp_path):
    f = tmp_path / "p.toml"
    f.write_text("v_max = 0.2\n[apf]\nd_o = 0.8\n[other]\nignored = 1\n")
    apf, _ = load_params("apf", f, ["k_theta=2", "apf.scale_to_scan=false"])
    assert (apf.v_max, apf.d_o, apf.k_theta, apf.scale_to_scan) == (0.2, 0.8, 2.0, False)
    with pytest.raises(ConfigError, match="unknown apf setting 'nope'"):
        load_params("apf", None, ["nope=1"])
    with pytest.raises(ConfigError, match=r"d_o=far: must be a finite number in \[0.25, 25\] m"):
        load_params("apf", None, ["d_o=far"])
    with pytest.raises(ConfigError, match="unknown planner 'xyz'"):
        make_planner("xyz")


# -- closed loop -------------------------------------------------------------------
def test_point_robot_reaches_goal_past_a_circle():
    world = toy_world(circles=((2.0, 0.6, 0.3),))
    r = simulate(make_planner("apf"), world, start=(0.0, 0.0, 0.0), goal=(4.0, 0.0),
                 max_time_s=120)
    assert r.status == "reached"
    assert np.hypot(r.path[-1, 0] - 4.0, r.path[-1, 1]) <= 0.1 + P.v_max * 0.1
    assert r.min_clearance > 0.15   # the robot's half size: no collision


def test_point_robot_open_field_is_deterministic():
    a = simulate(make_planner("apf"), toy_world(), goal=(2.0, 1.0), max_time_s=60)
    b = simulate(make_planner("apf"), toy_world(), goal=(2.0, 1.0), max_time_s=60)
    assert a.status == "reached" and np.array_equal(a.path, b.path)


@pytest.mark.parametrize("tolerance", [0.0, 1e-300, -5.0])
def test_a_bus_goal_with_a_tolerance_below_the_floor_is_reached_at_the_floor(tolerance):
    import math

    import numpy as np

    from common.robot import GOAL_TOLERANCE_MIN_M
    from nodes.planner.apf.strategy import APFStrategy
    from nodes.planner.core import Planner
    from schemas.messages import Goal, Odometry, Scan

    pl = Planner(APFStrategy())
    pl.set_goal(Goal(stamp_ns=1, x=1.0, y=0.0, tolerance=tolerance))
    scan = Scan(stamp_ns=2, angle_min=0.0, angle_increment=2 * math.pi / 8, range_min=0.2,
                range_max=10.0, ranges=np.full(8, np.inf, dtype=np.float32))
    near = 1.0 - 0.9 * GOAL_TOLERANCE_MIN_M
    status = pl.step(scan, Odometry(stamp_ns=2, x=near, y=0.0, yaw=0.0, v=0.0, w=0.0))[2]
    assert status.state == "reached"


def test_scans_of_ever_new_lengths_keep_the_planner_memory_bounded():
    import math

    import numpy as np

    from nodes.planner.apf.strategy import APFStrategy
    from nodes.planner.core import Planner
    from schemas.messages import Goal, Odometry, Scan

    pl = Planner(APFStrategy())
    pl.set_goal(Goal(stamp_ns=1, x=5.0, y=0.0))
    for n in range(1, 300):
        scan = Scan(stamp_ns=n, angle_min=0.0, angle_increment=2 * math.pi / n, range_min=0.2,
                    range_max=10.0, ranges=np.full(n, 3.0, dtype=np.float32))
        pl.step(scan, Odometry(stamp_ns=n, x=0.0, y=0.0, yaw=0.0, v=0.0, w=0.0))
    assert len(pl._apf_for_l) <= 16
