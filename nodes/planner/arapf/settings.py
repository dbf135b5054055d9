"""Declared type and valid range of every ARAPF parameter (see :mod:`nodes.planner.settings`)."""

from __future__ import annotations

from common.params import FLAG, Spec, choice, integer, num, pos
from common.robot import LIDAR_RANGE_MAX_M
from nodes.planner.settings import MAX_GAIN

ARAPF: dict[str, Spec] = {
    "k_ro_l": pos(MAX_GAIN, safety=True),
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
