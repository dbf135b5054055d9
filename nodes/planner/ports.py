"""Ports of the planner node (see :mod:`common.ports`)."""

PORTS = (
    ("in", "scan", "Scan"),                      # each scan -> one cycle
    ("in", "odom", "Odometry"),                  # paired with the scan
    ("in", "goal", "Goal"),                      # answered with status ready; carries the road
    ("out", "cmd_vel", "Twist"),                 # one per scan, stamp_ns = scan stamp
    ("out", "planner/state", "PlannerState"),    # debug geometry
    ("out", "planner/status", "PlannerStatus"),
)
VARIANTS: dict = {}
EXTRAS = {"--objects": (("in", "objects", "Objects"),)}   # obstacle tracks, paired with the scan
