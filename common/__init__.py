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

# One BLAS thread per process, set before numpy loads (every entry point imports `common`
# first: papf/__init__.py, nodes/__init__.py, schemas). The stack's arrays are small (a scan
# of ≤ 720 beams, a few dozen obstacles) and its parallelism is one process per node, so
# OpenBLAS's pool of a thread per core only costs: CPU at every process start and threads
# beside the other nodes (docs/performance.md "The test suite's time"). A value the user set
# is kept.
import os as _os

_os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
