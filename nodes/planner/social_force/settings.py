"""Declared type and valid range of every social-force planner parameter
(:mod:`nodes.planner.settings`).

The obstacle force's floor keeps the walls' and bodies' repulsion on: at its lower end it is
still a tenth of the library's default (10).
"""

from __future__ import annotations

from common.params import Spec, num, pos

SOCIAL_FORCE: dict[str, Spec] = {
    "relaxation_s": pos(10.0, "s"),
    "social_factor": num(0.0, 100.0),
    "obstacle_factor": num(1.0, 100.0, safety=True),
    "obstacle_sigma_m": pos(2.0, "m"),
    "safety_m": num(0.02, 1.0, "m", safety=True),
    "obstacle_range_m": pos(10.0, "m"),
    "neighbor_dist_m": pos(25.0, "m"),
    "group_gap_m": num(0.0, 2.0, "m"),
}
