"""Declared type and valid range of every PAPF parameter (see :mod:`nodes.planner.settings`)."""

from __future__ import annotations

from common.params import FLAG, Spec, integer, num, pos
from common.robot import LIDAR_RANGE_MAX_M

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
