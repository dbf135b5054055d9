"""ORCA as the robot's planner (van den Berg et al. 2011), on the RVO2 library (pyrvo).

A planner plug-in: :data:`STRATEGIES` is what :mod:`nodes.planner.registry` finds here.
"""

from nodes.planner.orca.strategy import ORCAStrategy

STRATEGIES = (ORCAStrategy,)
