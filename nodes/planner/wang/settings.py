"""Declared type and valid range of every Wang parameter (see :mod:`nodes.planner.settings`)."""

from __future__ import annotations

from common.params import Spec, integer, num, pos
from common.robot import LIDAR_RANGE_MAX_M
from nodes.planner.settings import MAX_BEAMS, MAX_GAIN

# Safety floors, measured as nodes/planner/settings.py's (docs/planners.md "Safety floors")
K_REP_L_MIN = 5.0        # [-] Wang's k_rep * L (1 collided on energy-blocking: the default is the floor)
RHO_0_MIN_M = 0.5        # [m] Wang's influence radius (0.3 collided on energy-blocking)
# Ceilings, measured upwards (`papf experiment safety-floor --attraction`)
K_ATT_MAX = 20.0         # [-] k_att (30 collided on energy-blocking)
WANG_RATIO_MAX = 4.0     # [-] k_att / k_rep_l (5 collided: k_rep_l = 10, k_att = 50)
CONTROL_OFFSET_MAX_M = 0.4   # [m] the force's point ahead of the robot (0.5 collided on both worlds)

WANG: dict[str, Spec] = {
    "k_att": pos(K_ATT_MAX, safety=True),
    "k_rep_l": num(K_REP_L_MIN, MAX_GAIN, safety=True),
    "lidar_points": integer(1, MAX_BEAMS),
    "rho_0": num(RHO_0_MIN_M, LIDAR_RANGE_MAX_M, "m", safety=True),
    "r_0": num(0.0, 5.0, "m"),
    "control_offset_m": num(0.0, CONTROL_OFFSET_MAX_M, "m"),
}

# Wang's traditional APF baseline (eqs. 1-5): the paper's failing baseline. Its floors are
# the paper's own values (Table 1's K_rep = 2 spread over the beams; rho_0 as the improved
# planner's measured floor): below them it is no reading of the paper, only a weaker field.
K_REP_L_BASELINE_MIN = 2.0   # [-] Table 1
WANG_APF: dict[str, Spec] = {
    "k_att": pos(K_ATT_MAX, safety=True),
    "k_rep_l": num(K_REP_L_BASELINE_MIN, MAX_GAIN, safety=True),
    "lidar_points": integer(1, MAX_BEAMS),
    "rho_0": num(RHO_0_MIN_M, LIDAR_RANGE_MAX_M, "m", safety=True),
}
