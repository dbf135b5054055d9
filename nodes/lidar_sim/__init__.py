"""lidar_sim node."""
