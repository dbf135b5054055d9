"""Ports of the world simulator (see :mod:`common.ports`): on the bus it is the base driver of
every simulated robot (its keys and liveliness token ``base_driver``), plus the ground truth."""

PORTS = (
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
VARIANTS: dict = {}
