"""The real ROSbot's base driver (``python -m nodes.base_driver --driver rosbot``).

What stands between our commands and the robot's controller: the command gate and its limits
(``common/drive.py``, shared with the world simulator), the robot's topics and odometry in the
run's frame (``rosbot.py``), the process (``rosbot_node.py``), and on a slow link the plan
follower (``follow.py``) and the collision monitor on the robot's own scan (``monitor.py``),
joined in ``link_drive.py``. The simulated robots are the world simulator's
(``nodes/world_sim``); ``--driver sim`` hands over to it.
"""
