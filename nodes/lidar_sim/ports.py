"""Ports of the LiDAR source (see :mod:`common.ports`): simulated (``PORTS``; ``ODOM`` in HIL), or
the robot's real sensor (``ROS2``, ``--source ros2``)."""

PORTS = (
    ("in", "sim/pose", "Odometry"),      # the world simulator's ground-truth pose (--pose-source sim, default)
    ("in?", "sim/bodies", "Bodies"),     # a fleet's other robots and people, per scan instant
    ("out", "scan", "Scan"),             # one per scan instant, stamped with the pose's stamp
)
ODOM = (
    ("in", "odom", "Odometry"),          # odometry pose (--pose-source odom: hardware in the loop)
    ("out", "scan", "Scan"),
)
ROS2 = (
    ("in", "clock", "Clock"),            # the robot driver's run time, to stamp the scans
    ("in", "bridge:scan", "sensor_msgs/LaserScan"),
    ("out", "scan", "Scan"),
)
VARIANTS = {("--source", "ros2"): ROS2, ("--pose-source", "odom"): ODOM}
EXTRAS = {"--truth-objects": (("out", "objects", "Objects"),)}   # the sim's ground truth
