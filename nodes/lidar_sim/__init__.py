"""The LiDAR source: the simulated RPLIDAR or the robot's real one, one node either way.

Simulated (the default): ``core.py`` casts the scan's rays in the world (pybullet) at the
world simulator's ground-truth pose (or the robot's odometry in HIL). Real
(``--source ros2``): ``ros2_source.py`` republishes the robot's own ROS 2 ``LaserScan`` as our
``scan`` on the run's clock. Both publish the same ``scan`` (``ports.py``).
"""
