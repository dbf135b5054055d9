"""The bottom layer: what every process of the stack shares.

- :mod:`common.errors` — the one error hierarchy (``PapfError`` and its subclasses);
- :mod:`common.transport` — Zenoh sessions, typed publishers, decoding subscribers;
- :mod:`common.ros2` — the ROS 2 CDR codec for the ``zenoh-bridge-ros2dds`` keys;
- :mod:`common.units` — time units and conversions (integer nanoseconds on the wire);
- :mod:`common.robot` — the ROSbot 2.0 PRO's facts (dimensions, mass, limits).

Imports point down only: ``schemas`` and ``common`` ← ``nodes`` ← ``papf`` (docs/architecture.md).
"""

# the one version of papf-stack: the package metadata (pyproject.toml reads it), `papf --version`,
# recordings' headers and metadata all take it from here
__version__ = "0.3.0"
