"""Optional imports in one place: numba (the pyproject extra ``fast``) and tomllib.

The planner and tracker kernels compile with numba when it is installed and run their
numpy / plain-Python twins otherwise; worlds, launch profiles and planner parameter files
are TOML, read by the standard library's ``tomllib`` (Python >= 3.11) or ``tomli`` before.
"""

from __future__ import annotations

import importlib
import importlib.util
from types import ModuleType

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10: the same parser as the package tomli
    import tomli as tomllib  # type: ignore[no-redef]

__all__ = ["HAVE_NUMBA", "numba_or_none", "tomllib"]

# whether numba is installed, found without importing it (its import costs ~0.5 s of CPU)
HAVE_NUMBA = importlib.util.find_spec("numba") is not None


def numba_or_none() -> ModuleType | None:
    """numba, imported now, or None when it is not installed."""
    return importlib.import_module("numba") if HAVE_NUMBA else None
