"""Declared type and valid range of every planner parameter (see :mod:`common.params`).

One table per params dataclass; :data:`SPECS` maps the class to its table and a test
checks that every field has a spec and every default lies in it. Safety parameters
(``safety=True``) are those that keep obstacle avoidance and the speed limits on:
a repulsion range, gain or charge of the wrong sign, a zero or infinite range, or a
speed above the ROSbot's limits is refused, so no setting can switch avoidance off.

Charges: the PAPF paper's force between two charges is ``-k q_a q_b / d^2`` along the
line (eq. 2), so obstacles repel only while ``q_V`` and ``q_O`` (and the quark charge
``q_Q``) share a sign, and the goal attracts only while ``q_G`` has the other one. The
ranges fix the paper's signs: ``q_V, q_O, q_Q < 0 < q_G``.
"""

from __future__ import annotations

from common.errors import ConfigError
from common.params import FLAG, Spec, choice, integer, num, pos
from common.robot import LIDAR_RANGE_MAX_M, V_MAX_M_S, W_MAX_RAD_S
from nodes.planner.apf import APFParams
from nodes.planner.arapf import ARAPFParams
from nodes.planner.iapf import IAPFParams
from nodes.planner.papf import PAPFParams
from nodes.planner.wang import WangAPFParams, WangParams

MAX_BEAMS = 100_000      # [-] LiDAR points a planner is configured for
MAX_GAIN = 1e4           # [-] largest force constant (defaults are 1 .. 10)

# Safety floors, measured (docs/planners.md "Safety floors", docs/data/safety-floor.csv:
# `papf experiment safety-floor`, offline on energy-blocking and papf-test-1): each the
# smallest swept value at which no run of any planner collided, the others at their
# defaults. A value just above zero switches avoidance off as surely as zero does.
D_O_MIN_M = 0.25         # [m] repulsion range (0.2 collided on both worlds)
K_VO_L_MIN = 1.0         # [-] k_VO * L (0.5 collided: PAPF on both worlds)
CHARGE_MIN = 0.2         # [-] |q_V|, |q_O| (0.1 collided: PAPF on energy-blocking)
K_RO_L_MIN = 0.5         # [-] AR-APF's k_RO * L (0.1 collided on papf-test-1)
K_REP_L_MIN = 5.0        # [-] Wang's k_rep * L (1 collided on energy-blocking: the default is the floor)
RHO_0_MIN_M = 0.5        # [m] Wang's influence radius (0.3 collided on energy-blocking)
# The single floors do not compose: eq. 2 repels with the product k_VO q_V q_O, so it has a
# floor of its own (each factor at its floor would be 250 times weaker than the default).
REPULSION_MIN = 2.0      # [-] k_vo_l * q_v * q_o (1 collided: q_o = -0.1 with PAPF)
AR_REPULSION_MIN = 0.5   # [-] AR-APF's k_ro_l * q_v * q_o

APF: dict[str, Spec] = {
    "lidar_points": integer(1, MAX_BEAMS),
    "q_v": num(-100.0, -CHARGE_MIN, safety=True),
    "q_o": num(-100.0, -CHARGE_MIN, safety=True),
    "q_g": num(0.0, 100.0, lo_open=True),
    "k_vg": pos(MAX_GAIN),
    "k_vo_l": num(K_VO_L_MIN, MAX_GAIN, safety=True),
    "d_o": num(D_O_MIN_M, LIDAR_RANGE_MAX_M, "m", safety=True),
    "theta_err_max_deg": pos(180.0, "deg"),
    "v_max": pos(V_MAX_M_S, "m/s", safety=True),
    "k_theta": pos(100.0, "1/s"),
    "w_max": pos(W_MAX_RAD_S, "rad/s", safety=True),
    "scale_to_scan": FLAG,
    "stagnation_window_s": pos(3600.0, "s"),
    "stagnation_progress_m": pos(10.0, "m"),
    "stagnation_roam_m": pos(100.0, "m"),
    "stagnation_max_s": pos(86_400.0, "s"),
}

PAPF: dict[str, Spec] = {
    "horizon_m": pos(10.0, "m"),
    "step_m": num(0.001, 1.0, "m"),
    "stag_fraction": pos(1.0),
    "stag_radius_fraction": pos(1.0),
    "k_vq_factor": num(0.0, 1000.0),
    "q_q": num(-100.0, 0.0, hi_open=True, safety=True),
    "max_quarks": integer(0, 1000),
    "d_q": pos(LIDAR_RANGE_MAX_M, "m"),
    "quark_ball_m": num(0.0, 5.0, "m"),
    "tie_tol_m": num(0.0, 1.0, "m"),
    "use_numba": FLAG,
    "persist_quarks": FLAG,
    "pull_range_fraction": num(0.0, 100.0),
    "motion_quarks_within_d_o": FLAG,
    "unresolved_global_goal": FLAG,
    "stop_at_goal": FLAG,
    "quark_restarts_watch": FLAG,
    "replace_oldest_quark": FLAG,
}

ARAPF: dict[str, Spec] = {
    "k_ro_l": num(K_RO_L_MIN, MAX_GAIN, safety=True),
    "k_virtual_factor": num(0.0, 1000.0),
    "alpha_deg": pos(180.0, "deg"),
    "d_min": pos(LIDAR_RANGE_MAX_M, "m"),
    "s_min": pos(10.0, "m"),
    "d_max": pos(5.0, "m"),
    "n_wall": integer(2, 1000),
    "beta_deg": pos(180.0, "deg"),
    "delta_gamma_deg": pos(180.0, "deg"),
    "range_limited": FLAG,
    "wall_range_limited": FLAG,
    "obstacle_offset_m": num(0.0, 5.0, "m"),
    "follow": FLAG,
    "passage_width": choice("opening", "gap"),
}

WANG: dict[str, Spec] = {
    "k_att": pos(1000.0),
    "k_rep_l": num(K_REP_L_MIN, MAX_GAIN, safety=True),
    "lidar_points": integer(1, MAX_BEAMS),
    "rho_0": num(RHO_0_MIN_M, LIDAR_RANGE_MAX_M, "m", safety=True),
    "r_0": num(0.0, 5.0, "m"),
    "control_offset_m": num(0.0, 1.0, "m"),
}

# Wang's traditional APF baseline (eqs. 1-5): the paper's failing baseline, its floors not
# measured (its default k_rep_l = 2 is below the improved planner's measured floor)
WANG_APF: dict[str, Spec] = {
    "k_att": pos(1000.0),
    "k_rep_l": pos(MAX_GAIN, safety=True),
    "lidar_points": integer(1, MAX_BEAMS),
    "rho_0": pos(LIDAR_RANGE_MAX_M, "m", safety=True),
}

# IAPF (Yang et al.): car-scale road planner; Table 1 values and ours (nodes/planner/iapf.py).
# Its a_x, a_y are negative by the paper's eq. 11 (the obstacle field decays with them).
IAPF: dict[str, Spec] = {
    "k1": pos(1e4), "k2": pos(1e4), "b1": num(0.0, 1e4), "b2": num(0.0, 1e4), "b3": num(0.0, 1e4),
    "a_x": num(-100.0, 0.0, "1/m^2", hi_open=True, safety=True),
    "a_y": num(-100.0, 0.0, "1/m^2", hi_open=True, safety=True),
    "eta1": num(0.0, 100.0), "eta2": num(0.0, 100.0),
    "step_s": pos(1.0, "s"), "horizon_s": pos(60.0, "s"),
    "s_m": pos(100.0, "m", safety=True), "a_b": pos(20.0, "m/s^2", safety=True),
    "f_step": integer(1, 1000), "c_f": integer(1, 1000), "t_c": pos(60.0, "s"),
    "v_cruise": pos(50.0, "m/s"), "obstacle_gain": pos(1e6, safety=True), "mass": pos(1e5, "kg"),
    "a_max": pos(20.0, "m/s^2"), "v_max_factor": num(1.0, 3.0),
    "predict_step_s": pos(5.0, "s"), "goal_half_period_lanes": pos(100.0),
    "b3_temp": num(0.0, 1e4), "heading_max_deg": pos(90.0, "deg"),
    "yaw_rate_max_deg": num(0.0, 3600.0, "deg/s"), "host_length": pos(20.0, "m"),
    "host_width": pos(10.0, "m"), "literal_rotation": FLAG, "prediction": FLAG,
    "traditional": FLAG, "k_trad": pos(1e7), "lane_width_ref": pos(20.0, "m"),
    "cruise_speed": pos(V_MAX_M_S, "m/s", safety=True),
    "brake_priority": FLAG, "follow_min_frac": num(0.0, 1.0), "goal_lane_s": num(0.0, 600.0, "s"),
    "stop_decel_frac": num(0.0, 1.0), "node_stop_decel_frac": num(0.0, 1.0),
    "heading_min_speed": num(0.0, 50.0, "m/s"),
}

SPECS: dict[type, dict[str, Spec]] = {
    APFParams: APF, PAPFParams: PAPF, ARAPFParams: ARAPF, WangParams: WANG, IAPFParams: IAPF,
    WangAPFParams: WANG_APF,
}


def check_strength(apf: APFParams, algo) -> None:
    """The products of eq. 2 above their floors (:data:`REPULSION_MIN`); ConfigError, one line."""
    products = [("k_vo_l*q_v*q_o", apf.k_vo_l * apf.q_v * apf.q_o, REPULSION_MIN)]
    if isinstance(algo, ARAPFParams):
        products.append(("k_ro_l*q_v*q_o", algo.k_ro_l * apf.q_v * apf.q_o, AR_REPULSION_MIN))
    for name, value, floor in products:
        if not value >= floor:
            raise ConfigError(f"{name} = {value:g}: the obstacle repulsion must be at least "
                              f"{floor:g} (below it the robot collides; docs/planners.md "
                              "\"Safety floors\")")


def specs_of(params_cls: type) -> dict[str, Spec]:
    """The table of a params class (a class with no fields has an empty one)."""
    return SPECS.get(params_cls, {})


# The planner node's own options (python -m nodes.planner): the stale-input stop is a
# safety setting — past 2 s a robot drives on data that no longer describes the world.
NODE: dict[str, Spec] = {
    "stale_timeout": pos(2.0, "s", safety=True),
    "pair_timeout": pos(10.0, "s"),
}
