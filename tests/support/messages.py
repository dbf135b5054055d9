"""Small messages the planner-node tests of every tier feed: a standing robot, an empty scan."""

from __future__ import annotations

import numpy as np

from schemas.messages import Odometry, Scan


def odom(t: int, x: float = 0.0) -> Odometry:
    """Odometry at ``t`` [ns]: standing at (``x`` [m], 0), heading +x."""
    return Odometry(stamp_ns=t, x=x, y=0.0, yaw=0.0, v=0.0, w=0.0)


def scan(t: int, n: int = 16) -> Scan:
    """A scan at ``t`` [ns] of ``n`` beams round the robot that see nothing (all inf)."""
    return Scan(stamp_ns=t, angle_min=0.0, angle_increment=2 * np.pi / n, range_min=0.2,
                range_max=10.0, ranges=np.full(n, np.inf, dtype=np.float32))


def scan_63(t: int) -> Scan:
    """A scan at ``t`` [ns] of 63 beams 0.1 rad apart from angle 0 that see nothing (all inf):
    what the stamp tests of the node intake and the planner loop feed."""
    return Scan(stamp_ns=t, angle_min=0.0, angle_increment=0.1, range_min=0.1, range_max=10.0,
                ranges=np.full(63, np.inf, np.float32))


def planner_debug(planner: str, **values) -> tuple:
    """``PlannerState.debug`` of registered ``planner`` with these values of its declared
    fields (the others empty), for states built by hand."""
    from nodes.planner.debug import debug_values
    from nodes.planner.registry import PLANNERS

    cls = PLANNERS[planner]
    return debug_values(cls.name, cls.DEBUG, values)
