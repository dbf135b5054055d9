"""IAPF (Jin et al., Symmetry 2024): car-scale road planner on obstacle tracks.

A planner plug-in: :data:`STRATEGIES` is what :mod:`nodes.planner.registry` finds here.
"""

from nodes.planner.iapf.strategy import IAPFStrategy

STRATEGIES = (IAPFStrategy,)
