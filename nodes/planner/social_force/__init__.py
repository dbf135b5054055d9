"""The social-force model as the robot's planner (Helbing & Molnár 1995; pysocialforce).

A planner plug-in: :data:`STRATEGIES` is what :mod:`nodes.planner.registry` finds here.
"""

from nodes.planner.social_force.strategy import SocialForceStrategy

STRATEGIES = (SocialForceStrategy,)
