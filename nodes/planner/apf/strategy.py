"""Classic APF (PAPF paper eq. 2) as a planner strategy."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from nodes.planner.apf.settings import APF_OWN
from nodes.planner.core import Plan, ScanView, Strategy
from nodes.planner.field import APFParams, apf_force


class APFStrategy(Strategy):
    """Classic APF (PAPF paper eq. 2): steer by the resultant force towards the global goal."""

    name = "apf"
    rank = 0
    roles = ("compared", "traffic", "crowd", "papf-baseline")
    colour, colour_map = "tab:blue", "Blues"
    PAPER_PRESET: dict = {}   # eq. 2 as written already: no deviation to switch off
    SPECS = APF_OWN

    @dataclass(frozen=True)
    class Params:
        """Classic APF has no settings beyond :class:`APFParams`."""

    def plan(self, pos: np.ndarray, yaw: float, goal: np.ndarray, view: ScanView,
             apf: APFParams) -> Plan:
        """Eq. 2 at ``pos`` [m] towards the global goal; no memory, no debug geometry."""
        return Plan(force=apf_force(pos, goal, view.points, apf))
