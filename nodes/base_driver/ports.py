"""Ports of the base driver (see :mod:`common.ports`); ``--driver rosbot`` has its own."""

SIM = (
    ("in", "events", "Event"),           # run_started: a new run at t = 0; run_ended stops it
    ("in", "cmd_vel", "Twist"),          # stamp_ns = the scan it answers (lockstep)
    ("out", "sim/pose", "Odometry"),     # ground truth, every odometry instant
    ("out", "odom", "Odometry"),         # odometry (= ground truth in sim)
    ("out", "wheels", "WheelStates"),    # wheel speeds and motor torques
    ("out", "clock", "Clock"),           # sim time
    ("out", "events", "Event"),          # collision, watchdog_stop, node_fault
    ("out", "sim/bodies", "Bodies"),     # a fleet or people: the others, before sim/pose
    ("out", "sim/people", "People"),     # [[people]]: where they are, every instant
)
ROSBOT = (
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
PORTS = SIM
VARIANTS = {("--driver", "rosbot"): ROSBOT}
