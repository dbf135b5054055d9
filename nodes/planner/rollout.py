"""The planner's short plan for a slow link: its own motion law rolled forward (pure).

On a real link a command reaches the robot a round trip after the scan it answers
(docs/link-driving.md). So each command carries the poses the robot is meant to pass
through next: the motion law of docs/planners.md (eq. 5's speed, our heading controller)
integrated from the pose the command was computed for, towards the cycle's reference
heading theta* held fixed — what the planner would command if the field did not change.
The robot side (``nodes/base_driver/follow.py``) follows these poses with its own odometry,
so the command is used at the time it arrives, not at the time it was computed for.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from nodes.planner.field import APFParams, turn_rate, wrap_angle

SUBSTEPS = 5   # integration steps per plan step (midpoint rule; the arc error is < 1 mm at 0.9 m/s)


def rollout(x: float, y: float, yaw: float, theta_ref: float, speed: Callable[[float], float],
            apf: APFParams, dt_s: float, steps: int) -> tuple[float, ...]:
    """Poses ``(x, y, yaw)`` at ``0, dt_s, ..., steps * dt_s``, flattened (``Twist.plan``).

    ``speed(err)`` is the cycle's speed law for a heading error ``err`` [rad] (eq. 5 with the
    cycle's force, or a strategy's own); the turn rate is :func:`turn_rate` towards
    ``theta_ref``. Yaw is kept continuous (not wrapped) so the robot side interpolates it.
    """
    out = [x, y, yaw]
    h = dt_s / SUBSTEPS
    for _ in range(steps):
        for _ in range(SUBSTEPS):
            err = wrap_angle(theta_ref - yaw)
            v, w = speed(err), turn_rate(theta_ref, yaw, apf)
            mid = yaw + 0.5 * w * h
            x, y, yaw = x + v * h * math.cos(mid), y + v * h * math.sin(mid), yaw + w * h
        out += (x, y, yaw)
    return tuple(out)


def stop_plan(x: float, y: float, yaw: float, steps: int) -> tuple[float, ...]:
    """A plan that stays where the command was computed for (a stop)."""
    return (x, y, yaw) * (steps + 1)
