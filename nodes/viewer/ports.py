"""Ports of the viewer node (see :mod:`common.ports`): every input is optional — it shows
what is there (no ``sim/pose`` on a real robot, no ``planner/state`` without a planner)."""

from nodes.viewer.core import SUBSCRIBED

_TYPES = {"scan": "Scan", "odom": "Odometry", "sim/pose": "Odometry", "goal": "Goal",
          "planner/state": "PlannerState", "planner/status": "PlannerStatus",
          "cmd_vel": "Twist", "battery": "BatteryState", "events": "Event",
          "objects": "Objects", "sim/bodies": "Bodies"}

PORTS = tuple(("in?", key, _TYPES[key]) for key in SUBSCRIBED) + (
    ("out", "goal", "Goal"),    # a pose/point published from Foxglove's 3D panel (--goals accept)
)
# Not topics: the query <ns>/planner/params (the Parameters panel) and ws://HOST:PORT.
QUERIES = ("planner/params",)
VARIANTS: dict = {}
