"""Declared type and valid range of every Wang parameter (see :mod:`nodes.planner.settings`)."""

from __future__ import annotations

from common.params import Spec, integer, num, pos
from common.robot import LIDAR_RANGE_MAX_M
from nodes.planner.settings import MAX_BEAMS, MAX_GAIN

WANG: dict[str, Spec] = {
    "k_att": pos(1000.0),
    "k_rep_l": pos(MAX_GAIN, safety=True),
    "lidar_points": integer(1, MAX_BEAMS),
    "rho_0": pos(LIDAR_RANGE_MAX_M, "m", safety=True),
    "r_0": num(0.0, 5.0, "m"),
    "control_offset_m": num(0.0, 1.0, "m"),
}

# Wang's traditional APF baseline (eqs. 1-5)
WANG_APF: dict[str, Spec] = {
    "k_att": pos(1000.0),
    "k_rep_l": pos(MAX_GAIN, safety=True),
    "lidar_points": integer(1, MAX_BEAMS),
    "rho_0": pos(LIDAR_RANGE_MAX_M, "m", safety=True),
}
