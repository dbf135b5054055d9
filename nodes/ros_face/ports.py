"""Ports of the ROS 2 face (see :mod:`common.ports`): every input is optional — it shows
what is there. Its ROS 2 side (rmw_zenoh keys of ``/scan``, ``/odom``, …, ``/goal_pose``,
the parameter services and ``navigate_to_pose``) is listed by ``python -m nodes.ros_face --help``."""

PORTS = (
    ("in?", "scan", "Scan"),
    ("in?", "odom", "Odometry"),
    ("in?", "cmd_vel", "Twist"),
    ("in?", "battery", "BatteryState"),
    ("in?", "planner/state", "PlannerState"),
    ("in?", "planner/status", "PlannerStatus"),   # navigate_to_pose: reached, stagnated, idle
    ("in?", "wheels", "WheelStates"),             # /joint_states, the wheels' /tf
    ("in?", "clock", "Clock"),                    # /clock (sim time)
    ("in?", "goal", "Goal"),            # the run's goal: a /goal_pose keeps its tolerance, road
    ("out", "goal", "Goal"),            # /goal_pose, navigate_to_pose (--goals accept)
)
# Not a topic: the query <ns>/planner/params (the ROS 2 parameter services ask it)
QUERIES = ("planner/params",)
VARIANTS: dict = {}
