"""AR-APF: adaptive repulsion, a virtual wall and obstacle across a local minimum.

A planner plug-in: :data:`STRATEGIES` is what :mod:`nodes.planner.registry` finds here.
"""

from nodes.planner.arapf.strategy import ARAPFStrategy

STRATEGIES = (ARAPFStrategy,)
