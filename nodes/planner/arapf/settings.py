"""Declared type and valid range of every ARAPF parameter (see :mod:`nodes.planner.settings`)."""

from __future__ import annotations

from common.params import FLAG, Spec, choice, integer, num, pos
from common.robot import LIDAR_RANGE_MAX_M
from nodes.planner.settings import MAX_GAIN

# Safety floors, measured as nodes/planner/settings.py's (docs/planners.md "Safety floors")
K_RO_L_MIN = 0.5         # [-] AR-APF's k_RO * L (0.1 collided on papf-test-1)
AR_REPULSION_MIN = 0.5   # [-] AR-APF's k_ro_l * q_v * q_o (the virtual obstacles' repulsion)

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
