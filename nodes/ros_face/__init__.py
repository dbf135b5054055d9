"""The stack's ROS 2 face over rmw_zenoh (``python -m nodes.ros_face``)."""
