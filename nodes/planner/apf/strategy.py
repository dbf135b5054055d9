"""Classic APF (PAPF paper eq. 2) as a planner strategy."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from nodes.planner.core import Plan, ScanView
from nodes.planner.field import APFParams, apf_force


class APFStrategy:
    """Classic APF (PAPF paper eq. 2): steer by the resultant force towards the global goal."""

    name = "apf"
    PAPER_PRESET: dict = {}   # eq. 2 as written already: no deviation to switch off

    @dataclass(frozen=True)
    class Params:
        """Classic APF has no settings beyond :class:`APFParams`."""

    def __init__(self, params: Params | None = None):
        self.params = params or self.Params()

    def reset(self) -> None:
        pass

    def plan(self, pos: np.ndarray, yaw: float, goal: np.ndarray, view: ScanView,
             apf: APFParams) -> Plan:
        return Plan(force=apf_force(pos, goal, view.points, apf))
