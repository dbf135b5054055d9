"""Classic APF (PAPF paper eq. 2): steer by the resultant force towards the global goal.

A planner plug-in: :data:`STRATEGIES` is what :mod:`nodes.planner.registry` finds here.
"""

from nodes.planner.apf.strategy import APFStrategy

STRATEGIES = (APFStrategy,)
