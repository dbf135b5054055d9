"""Ports of the tracker node (see :mod:`common.ports`)."""

PORTS = (
    ("in", "scan", "Scan"),              # each scan -> one tracker cycle
    ("in", "odom", "Odometry"),          # the pose of the scan (same stamp in lockstep)
    ("out", "objects", "Objects"),       # confirmed tracks, stamped with the scan's stamp
)
VARIANTS: dict = {}
