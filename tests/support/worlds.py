"""World files the test tiers write: a short run past one box, and a two-lane road with a car.

The TOML text is what a user writes (``worlds`` parses it as it parses a packaged world).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

# 1 m straight ahead, nothing in the way: a real run through the whole stack in seconds
SHORT_WORLD = """
name = "short"
description = "1 m straight ahead (tests)"
[robot]
start = [0.0, 0.0, 0.0]
[goal]
position = [1.0, 0.0]
tolerance = 0.1
"""
FAST = ["--set", "v_max=0.5"]    # the paper's 0.1 m/s would make a test of a short world slow
# A run compared with another is bit-reproducible only while its lockstep holds: the suite's
# load (four workers, each starting processes, on two cores) once stalled a fleet's command
# past the simulator's 2 s wait, and the second of two runs differed (papf run --lockstep-timeout)
STEADY = ["--lockstep-timeout", "30"]


def box_world(name: str, description: str, goal_x: float, box_center: tuple[float, float],
              tolerance: float = 0.15) -> str:
    """From the origin to ``goal_x`` [m] straight ahead (``tolerance`` [m]), one 0.3 m box at
    ``box_center`` [m] beside the path."""
    return f"""name = "{name}"
description = "{description}"
[robot]
start = [0.0, 0.0, 0.0]
[goal]
position = [{goal_x}, 0.0]
tolerance = {tolerance}
[[obstacles]]
kind = "box"
center = [{box_center[0]}, {box_center[1]}]
size = [0.3, 0.3]
"""


SHORT = box_world("short", "1.2 m ahead, a box beside the path", 1.2, (0.6, 0.6))


def traffic_world(goal_x: float = 10.0,
                  track: Sequence[tuple[float, float, float]] = ((0.0, 3.0, 0.0), (20.0, 5.0, 0.0)),
                  extra: str = "") -> str:
    """The road issue's example: two 0.6 m lanes from y = -0.3 m, the goal ``goal_x`` [m]
    ahead, a 0.5 x 0.3 m box driving along ``track`` ((t [s], x [m], y [m]) knots); ``extra``
    (TOML) appended."""
    knots = ", ".join(f"[{t}, {x}, {y}]" for t, x, y in track)
    return f"""name = "traffic"
[goal]
position = [{goal_x}, 0.0]
[road]
y_min = -0.3
lane_width = 0.6
lanes = 2
[[obstacles]]
kind = "box"
size = [0.5, 0.3]
[obstacles.motion]
track = [{knots}]
{extra}"""


def write_world(path: Path, text: str) -> Path:
    """``text`` written to ``path``; ``path``."""
    path.write_text(text)
    return path
