"""Predictive APF (Szczepanski et al., IEEE Access 2022): prediction, top quarks, temporary goal.

A planner plug-in: :data:`STRATEGIES` is what :mod:`nodes.planner.registry` finds here.
"""

from nodes.planner.papf.strategy import PAPFStrategy

STRATEGIES = (PAPFStrategy,)
