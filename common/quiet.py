"""Import a module whose C part prints a banner at import time, without the banner.

pybullet writes ``pybullet build time: …`` to the process's stderr (file descriptor 2,
from C) when it is imported; every ``papf plan`` and node would show it. The descriptor is
pointed at /dev/null for the import only, so errors raised by the import still surface.
"""

from __future__ import annotations

import importlib
import os
import sys
from types import ModuleType


def import_quietly(name: str) -> ModuleType:
    """``import name`` with file descriptor 2 silenced while it runs."""
    if name in sys.modules:
        return sys.modules[name]
    sys.stderr.flush()
    saved = os.dup(2)
    null = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(null, 2)
        return importlib.import_module(name)
    finally:
        os.dup2(saved, 2)
        os.close(saved)
        os.close(null)
