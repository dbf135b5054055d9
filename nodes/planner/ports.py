"""Ports of the planner node (see :mod:`common.ports`)."""

PORTS = (
    ("in", "scan", "Scan"),                      # each scan -> one cycle
    ("in", "odom", "Odometry"),                  # paired with the scan
    ("in", "goal", "Goal"),                      # answered with status ready; carries the road
    ("out", "cmd_vel", "Twist"),                 # one per scan, stamp_ns = scan stamp
    ("out", "planner/state", "PlannerState"),    # debug geometry
    ("out", "planner/status", "PlannerStatus"),
    ("out", "events", "Event"),                  # info: a setting changed at run time
)
# Not a topic: the queryable <ns>/planner/params (JSON) lists and changes the settings at
# run time (nodes.planner.params; the viewer's Parameters panel uses it).
QUERYABLES = ("planner/params",)
VARIANTS: dict = {}
EXTRAS = {"--objects": (("in", "objects", "Objects"),)}   # obstacle tracks, paired with the scan
