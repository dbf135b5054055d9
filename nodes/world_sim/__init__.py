"""The world simulator (``python -m nodes.world_sim``): the simulated ROSbots and their world.

Physics (``physics.py``: pybullet, the tyres, the robots' bodies, the people's), the time grid,
the robots' command gates, people, fleets, collisions and the bodies each LiDAR sees
(``core.py``), the lockstep or real-time schedule (``loop.py``), its ports (``ports.py``).
On the bus it stands in the base driver's place (liveliness ``base_driver``): a simulated run
and a real one look alike to every other node.
"""
