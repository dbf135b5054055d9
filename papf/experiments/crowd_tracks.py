"""A recorded crowd of our own, in the ETH/UCY benchmarks' track format.

The real ETH and UCY recordings are not ours to ship (docs/worlds.md says where to get them).
To replay *something* recorded in the packaged world ``crowd-replay`` and in ``papf
experiment crowd``, this writes a file of the same form from a simulation of ours, run
without any robot: pedestrians enter a ``HALL`` (the crowd experiment's 11 x 6 m hall) at
seeded times through one of its four sides and cross it to the opposite side, avoiding each
other with ORCA (pyrvo; the crowd's parameters, common/crowd.py), each in the file from its
first step in to its arrival, as a real recording has people come and go. Rows ``frame id x
y`` every ``FRAME_STEP`` frames at 25 fps (2.5 Hz, as the benchmarks' files).

Replayed, these people do not see the robot: CrowdNav's "invisible robot" setting, the harder
test of a planner, beside the hall's ORCA people who step aside.

    python -m papf.experiments.crowd_tracks worlds/tracks/walkers-hall.txt   # the packaged file
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

from common.crowd import (
    ORCA_MAX_NEIGHBORS,
    ORCA_NEIGHBOR_DIST_M,
    ORCA_SAFETY_M,
    ORCA_TIME_HORIZON_OBST_S,
    ORCA_TIME_HORIZON_S,
)

HALL = ((-1.5, 9.5), (-3.0, 3.0))   # [m] x and y spans
FPS = 25.0                           # [1/s] of the frame column
FRAME_STEP = 10                      # [frames] between rows (0.4 s)
DT = 0.1                             # [s] simulation step
SPAWN_EVERY_S = (3.0, 8.0)           # [s] gap between arrivals, uniform
SPEED_M_S = (0.8, 1.4)               # [m/s] preferred speed, uniform
RADIUS_M = 0.25                      # [m] as the replay's default radius
ARRIVED_M = 0.3                      # [m] within this of its exit: gone
PARK = (1.0e4, 1.0e4)                # [m] where a gone pedestrian waits (out of everyone's way)


def _door(rng, side: int) -> tuple[float, float]:
    """A point on side 0-3 (x min, x max, y min, y max) of the hall, 0.3 m inside."""
    (x0, x1), (y0, y1) = HALL
    if side < 2:
        return (x0 + 0.3 if side == 0 else x1 - 0.3), float(rng.uniform(y0 + 0.5, y1 - 0.5))
    return float(rng.uniform(x0 + 0.5, x1 - 0.5)), (y0 + 0.3 if side == 2 else y1 - 0.3)


def walkers(duration_s: float, seed: int = 0) -> list[tuple[int, int, float, float]]:
    """Rows (frame, id, x, y) of the crowd (module doc), in frame order."""
    import pyrvo

    rng = np.random.default_rng(seed)
    sim = pyrvo.RVOSimulator()
    sim.set_time_step(DT)
    goals: dict[int, tuple[float, float]] = {}
    live: set[int] = set()
    rows: list[tuple[int, int, float, float]] = []
    next_in, t, step = 0.0, 0.0, 0
    every = round(FRAME_STEP / FPS / DT)
    while t < duration_s:
        if t >= next_in:
            side = int(rng.integers(4))
            start, goal = _door(rng, side), _door(rng, side ^ 1)
            k = sim.add_agent(start, ORCA_NEIGHBOR_DIST_M, ORCA_MAX_NEIGHBORS,
                              ORCA_TIME_HORIZON_S, ORCA_TIME_HORIZON_OBST_S,
                              RADIUS_M + ORCA_SAFETY_M, float(rng.uniform(*SPEED_M_S)),
                              (0.0, 0.0))
            goals[k] = goal
            live.add(k)
            next_in = t + float(rng.uniform(*SPAWN_EVERY_S))
        for k in list(live):
            (x, y), (gx, gy) = sim.get_agent_position(k).to_tuple(), goals[k]
            d = math.hypot(gx - x, gy - y)
            if d < ARRIVED_M:                       # gone through the door
                live.discard(k)
                sim.set_agent_position(k, (PARK[0] + 10.0 * k, PARK[1]))
                sim.set_agent_pref_velocity(k, (0.0, 0.0))
                continue
            v = sim.get_agent_max_speed(k)
            sim.set_agent_pref_velocity(k, ((gx - x) / d * v, (gy - y) / d * v))
        if step % every == 0:
            frame = step // every * FRAME_STEP
            rows += [(frame, k + 1, *sim.get_agent_position(k).to_tuple()) for k in sorted(live)]
        sim.do_step()
        step += 1
        t = step * DT
    return rows


def write_walkers(path: str | Path, duration_s: float = 600.0, seed: int = 0) -> Path:
    """The file (module doc): tab-separated as the benchmarks ship them (ids, frames as floats)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("".join(f"{f:.1f}\t{i:.1f}\t{x:.3f}\t{y:.3f}\n"
                            for f, i, x, y in walkers(duration_s, seed)), encoding="utf-8")
    return path


if __name__ == "__main__":
    out = write_walkers(sys.argv[1] if len(sys.argv) > 1 else "walkers-hall.txt")
    print(f"wrote {out}", file=sys.stderr)
