"""The stagnation watch of every planner: the core's (:class:`nodes.planner.core.Planner`) and
the offline 3-D point robot's (:mod:`papf.offline.point3d`) — one rule, any dimension."""

from __future__ import annotations

import math

import numpy as np

from common.units import NS_PER_S
from nodes.planner.field import APFParams

# [ns] a gap this long between two checks is time the planner did not steer (no scan reached
# it: a link outage, a sensor gone quiet), ten scan periods of the RPLIDAR's 10 Hz
INPUT_GAP_NS = 1_000_000_000


class StagnationWatch:
    """Stagnated when, within ``stagnation_window_s``, the robot makes no progress of
    ``stagnation_progress_m`` towards the goal and does not move ``stagnation_roam_m`` away
    from where the window began (nor searches, e.g. PAPF placing a quark); or when it makes
    no such progress within ``stagnation_max_s`` (ours, APFParams.stagnation_*).

    Time without input is not time without progress: a gap of :data:`INPUT_GAP_NS` or more
    between two checks (the planner got no scan: a link outage on a split) moves the
    window's and the last progress's times forward by the gap, so the robot is judged on
    the time it was steered. In simulation (lockstep, offline) no such gap occurs."""

    def __init__(self) -> None:
        self.reset()

    def reset(self) -> None:
        """Forget the run (a new goal)."""
        self.best = math.inf       # best distance to goal at the last progress [m]
        self.best_ns = 0           # time of the last progress [ns]
        self.window_ns = 0         # time the current window began [ns]
        self.anchor = None         # position where the current window began [m]
        self.last_ns: int | None = None   # time of the last check [ns]

    def check(self, t_ns: int, dist: float, apf: APFParams, pos=None, searching: bool = False) -> str:
        """At time ``t_ns`` [ns], ``dist`` [m] from the goal, at ``pos`` [m]: the reason, or ""."""
        if self.last_ns is not None and t_ns - self.last_ns >= INPUT_GAP_NS:
            gap = t_ns - self.last_ns
            self.best_ns += gap
            self.window_ns += gap
        self.last_ns = t_ns
        if dist < self.best - apf.stagnation_progress_m or not math.isfinite(self.best):
            self.best, self.best_ns = dist, t_ns
            self.window_ns, self.anchor = t_ns, pos
            return ""
        if searching or (pos is not None and self.anchor is not None
                         and _length(np.asarray(pos) - self.anchor) > apf.stagnation_roam_m):
            self.window_ns, self.anchor = t_ns, pos
        if t_ns - self.window_ns > apf.stagnation_window_s * NS_PER_S:
            return (f"no progress > {apf.stagnation_progress_m} m towards the goal in "
                    f"{apf.stagnation_window_s} s (best {self.best:.3f} m)")
        if t_ns - self.best_ns > apf.stagnation_max_s * NS_PER_S:
            return (f"no progress > {apf.stagnation_progress_m} m towards the goal in "
                    f"{apf.stagnation_max_s} s (best {self.best:.3f} m)")
        return ""


def _length(d: np.ndarray) -> float:
    """|d| [m]; ``np.hypot`` in 2-D (the rounding the planner always had)."""
    return float(np.hypot(d[0], d[1])) if d.shape[0] == 2 else float(np.linalg.norm(d))
