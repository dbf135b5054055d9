"""Declared type and valid range of every ORCA planner parameter (:mod:`nodes.planner.settings`).

The safety margin's floor keeps a margin around the robot's circumscribed disc: 0 would let
RVO2 plan to graze people (the range's lower end is a real margin, not "off").
"""

from __future__ import annotations

from common.params import Spec, integer, num, pos

SAFETY_MIN_M = 0.02        # [m] the least margin around the robot's disc

ORCA: dict[str, Spec] = {
    "time_horizon_s": pos(20.0, "s"),
    "time_horizon_obst_s": pos(20.0, "s"),
    "neighbor_dist_m": pos(25.0, "m"),
    "max_neighbors": integer(1, 100),
    "safety_m": num(SAFETY_MIN_M, 1.0, "m", safety=True),
    "obstacle_range_m": pos(10.0, "m"),
    "group_gap_m": num(0.0, 2.0, "m"),
}
