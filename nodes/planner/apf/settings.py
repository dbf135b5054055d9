"""Declared type and valid range of every classic-APF parameter (see :mod:`nodes.planner.settings`).

Classic APF has none beyond the shared :data:`nodes.planner.settings.APF`.
"""

from __future__ import annotations

from common.params import Spec

APF_OWN: dict[str, Spec] = {}
