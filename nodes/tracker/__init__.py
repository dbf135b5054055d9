"""The obstacle tracker node: LiDAR scans + odometry -> object tracks (``python -m nodes.tracker``)."""
