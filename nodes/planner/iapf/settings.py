"""Declared type and valid range of every IAPF parameter (see :mod:`nodes.planner.settings`)."""

from __future__ import annotations

from common.params import FLAG, Spec, integer, num, pos
from common.robot import V_MAX_M_S

# IAPF (Yang et al.): car-scale road planner; Table 1 values and ours (nodes/planner/iapf/algorithm.py).
# Its a_x, a_y are negative by the paper's eq. 11 (the obstacle field decays with them).
# Safety floors (docs/planners.md "Safety floors", `papf experiment safety-floor --car`,
# docs/data/safety-floor-iapf.csv): towards 0 the field stops decaying and its gradient, the
# avoiding force, vanishes; a_x = -1e-4 collided in case D, a_y held to the last value swept.
A_X_MAX = -3e-4          # [1/m^2] the smallest magnitude at which no case collided
A_Y_MAX = -1e-3          # [1/m^2] the smallest magnitude swept (none collided)
# Caps on the strong side (issue 31): a steep decay narrows the field to nothing around the
# obstacle, which switches avoidance off as surely as a zero gain. a_x = -0.3 and a_y = -3
# collided in case D (-0.1 and -1 held); a_x is capped at the paper's own Table 1 value -0.15
# (its literal preset), as obstacle_gain's floor is the paper's 1 — case D collides there with
# our other settings, as the literal preset's documented collision in D shows.
A_X_MIN = -0.15          # [1/m^2]
A_Y_MIN = -1.0           # [1/m^2]
OBSTACLE_GAIN_MAX = 1e5  # [-] the largest swept: no case collided up to it
# obstacle_gain: the paper's own amplitude 1 (Table 1 reading; --preset paper) is the floor —
# at 1 the field still steers cases A-C clear; case D needs >= 15 with our other settings,
# as the literal preset's documented collision in D shows.
OBSTACLE_GAIN_MIN = 1.0
IAPF: dict[str, Spec] = {
    "k1": pos(1e4), "k2": pos(1e4), "b1": num(0.0, 1e4), "b2": num(0.0, 1e4), "b3": num(0.0, 1e4),
    "a_x": num(A_X_MIN, A_X_MAX, "1/m^2", safety=True),
    "a_y": num(A_Y_MIN, A_Y_MAX, "1/m^2", safety=True),
    "eta1": num(0.0, 100.0), "eta2": num(0.0, 100.0),
    "step_s": pos(1.0, "s"), "horizon_s": pos(60.0, "s"),
    "s_m": pos(100.0, "m", safety=True), "a_b": pos(20.0, "m/s^2", safety=True),
    "f_step": integer(1, 1000), "c_f": integer(1, 1000), "t_c": pos(60.0, "s"),
    "v_cruise": pos(50.0, "m/s"), "obstacle_gain": num(OBSTACLE_GAIN_MIN, OBSTACLE_GAIN_MAX, safety=True), "mass": pos(1e5, "kg"),
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
