"""Wang's improved APF (``wang``) and his traditional APF baseline (``wang-apf``).

A planner plug-in: :data:`STRATEGIES` is what :mod:`nodes.planner.registry` finds here.
"""

from nodes.planner.wang.strategy import WangAPFStrategy, WangStrategy

STRATEGIES = (WangStrategy, WangAPFStrategy)
