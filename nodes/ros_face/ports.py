"""Ports of the ROS 2 face (see :mod:`common.ports`): every input is optional — it shows
what is there. Its ROS 2 side (rmw_zenoh keys of ``/scan``, ``/odom``, … and ``/goal_pose``)
is listed by ``python -m nodes.ros_face --help``."""

PORTS = (
    ("in?", "scan", "Scan"),
    ("in?", "odom", "Odometry"),
    ("in?", "cmd_vel", "Twist"),
    ("in?", "battery", "BatteryState"),
    ("in?", "planner/state", "PlannerState"),
    ("in?", "goal", "Goal"),            # the run's goal: a /goal_pose keeps its tolerance, road
    ("out", "goal", "Goal"),            # a /goal_pose from RViz (--goals accept)
)
VARIANTS: dict = {}
