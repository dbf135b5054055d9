"""What the launcher's fork server loads before it forks this node (papf/launch/forkserver.py)."""

from __future__ import annotations


def preload(argv: list[str]) -> None:
    """The physics (pybullet), imported by the node once it has read its world."""
    import nodes.world_sim.core  # noqa: F401
