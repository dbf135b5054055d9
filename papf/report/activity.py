"""What a planner did on a run, from its recording: how far it moved its temporary goal, how
many points it placed (issue 14: does an energy world make PAPF's mechanisms work?).

- **temporary-goal offset** [m]: per cycle, the distance of ``planner/state``'s temporary
  goal from the straight line through the robot (latest odometry) towards the global goal
  (the sideways move eq. 8 makes); the maximum over the run.
- **points away from the goal**: distinct points (1 cm grid) of the plug-in's own ``points``
  debug values (PAPF's: its top quarks) placed farther than :data:`NEAR_GOAL_M` from the
  goal. Quarks closer than that mark the prediction oscillating about the goal itself (the
  literal reading predicts past the goal, so its stagnation check fires there) and do not
  steer round obstacles.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from papf.recording.reader import iter_messages, read_metadata

NEAR_GOAL_M = 1.25   # [m] lambda + lambda_stag of Table 1


@dataclass(frozen=True)
class Activity:
    max_goal_offset_m: float
    quarks_away: int    # points away from the goal (PAPF: top quarks)


def papf_activity(path: str | Path) -> Activity:
    """The run's :class:`Activity` (0 and 0 for planners that publish no temporary goal)."""
    from worlds import load_world

    meta = read_metadata(path).get("run", {})
    world = meta.get("world", "")
    try:
        goal = np.array(load_world(world).goal[:2], float)
    except Exception:  # noqa: BLE001 - a world we cannot load: no goal line to measure against
        return Activity(math.nan, 0)
    pos, best, quarks = None, 0.0, set()
    for key, msg, _t in iter_messages(path, keys=["*/odom", "*/planner/state"]):
        if key.endswith("/odom"):
            pos = np.array([msg.x, msg.y])
            continue
        for q in (p for d in msg.debug if d.kind == "points" for p in d.points):
            if math.dist(q[:2], goal) > NEAR_GOAL_M:
                quarks.add((round(q[0], 2), round(q[1], 2)))
        if pos is None or not msg.temporary_goal:
            continue
        u = goal - pos
        n = float(np.linalg.norm(u))
        if n < 1e-9:
            continue
        rel = np.array(msg.temporary_goal[:2]) - pos
        best = max(best, abs(rel[0] * u[1] - rel[1] * u[0]) / n)
    return Activity(best, len(quarks))
