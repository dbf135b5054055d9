"""Ports of the real ROSbot's base driver (see :mod:`common.ports`).

``--driver sim`` hands over to the world simulator (``python -m nodes.world_sim``), whose
ports are its own (``nodes/world_sim/ports.py``)."""

PORTS = (
    ("in", "cmd_vel", "Twist"),
    ("in", "events", "Event"),           # run_started starts the run clock, run_ended stops it
    ("in?", "scan", "Scan"),             # the robot's own scan: the collision monitor's view
    ("in", "bridge:odometry/filtered", "nav_msgs/Odometry"),   # the robot's EKF
    ("in", "bridge:battery", "sensor_msgs/BatteryState"),      # pack voltage
    ("out", "bridge:cmd_vel", "geometry_msgs/Twist"),          # the gated command
    ("out", "odom", "Odometry"),
    ("out", "wheels", "WheelStates"),    # derived from odometry
    ("out", "clock", "Clock"),           # wall time since run_started
    ("out", "battery/measured", "BatteryVoltage"),
    ("out", "events", "Event"),          # watchdog_stop, node_fault, link_lost/_restored, command_refused
    ("out", "link", "LinkHealth"),       # the link as the robot measures it, every second of a run
    ("out", "cmd_vel/applied", "Twist"), # what went to the base (stamp = run time)
)
VARIANTS: dict = {}
