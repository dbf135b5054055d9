"""What the launcher's fork server loads before it forks this node (papf/launch/forkserver.py)."""

from __future__ import annotations


def preload(argv: list[str]) -> None:
    """The ray caster (pybullet), imported by the node once it has read its options, unless
    the scans come from ROS 2 (``--source ros2``)."""
    k = argv.index("--source") if "--source" in argv[:-1] else -1
    if k < 0 or argv[k + 1] == "sim":
        import nodes.lidar_sim.core  # noqa: F401
