"""Ports of the LiDAR node (see :mod:`common.ports`): simulated, or the real sensor's bridge."""

PORTS = (
    ("in", "sim/pose", "Odometry"),      # ground-truth pose (--pose-source sim, default)
    ("in?", "sim/bodies", "Bodies"),     # a fleet's other robots and people, per scan instant
    ("out", "scan", "Scan"),             # one per scan instant, stamped with the pose's stamp
)
ODOM = (
    ("in", "odom", "Odometry"),          # odometry pose (--pose-source odom: hardware in the loop)
    ("out", "scan", "Scan"),
)
ROS2 = (
    ("in", "clock", "Clock"),            # the driver's run time, to stamp the scans
    ("in", "bridge:scan", "sensor_msgs/LaserScan"),
    ("out", "scan", "Scan"),
)
VARIANTS = {("--source", "ros2"): ROS2, ("--pose-source", "odom"): ODOM}
EXTRAS = {"--truth-objects": (("out", "objects", "Objects"),)}   # the sim's ground truth
