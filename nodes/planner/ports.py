"""Ports of the planner node (see :mod:`common.ports`)."""

PORTS = (
    ("in", "scan", "Scan"),                      # each scan -> one cycle
    ("in", "odom", "Odometry"),                  # paired with the scan
    ("in", "goal", "Goal"),                      # answered with status ready
    ("out", "cmd_vel", "Twist"),                 # one per scan, stamp_ns = scan stamp
    ("out", "planner/state", "PlannerState"),    # debug geometry
    ("out", "planner/status", "PlannerStatus"),
)
VARIANTS: dict = {}
