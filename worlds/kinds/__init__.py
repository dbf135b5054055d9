"""Obstacle kinds, one class each (:class:`worlds.kinds.base.Kind`), by their TOML name.

A new kind: a module here with its class, and one line in :data:`KINDS` below.
"""

from __future__ import annotations

from worlds.kinds.base import Kind
from worlds.kinds.box import Box
from worlds.kinds.cylinder import Cylinder
from worlds.kinds.grid import Grid
from worlds.kinds.sphere import Sphere
from worlds.kinds.wall import Wall
from worlds.obstacle import KINDS

KINDS.update({k.name: k for k in (Box(), Cylinder(), Wall(), Sphere(), Grid())})


def register(kind: Kind) -> None:
    """Add ``kind`` under its TOML name (a kind outside this package: a plug-in, a test)."""
    KINDS[kind.name] = kind
