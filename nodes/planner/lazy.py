"""Modules loaded on first use: the numba kernels, only in a process whose planner runs them.

Importing numba and its first compiled call cost about a second of CPU; APF, AR-APF,
Wang and the launcher run no kernel. :mod:`nodes.planner.papf.strategy` and
:mod:`nodes.planner.iapf.algorithm` bind their kernel modules with :func:`lazy_module`:
the module's code (and numba's import) runs at its first attribute read.
"""

from __future__ import annotations

import importlib
import importlib.util
import sys
from types import ModuleType

from common.optional import HAVE_NUMBA  # noqa: F401 - read here by the planners (lazy.HAVE_NUMBA)


def lazy_module(name: str) -> ModuleType:
    """The module ``name``, executed at its first attribute access (``importlib.util.LazyLoader``).

    Already imported: that module. Later ``import name`` statements get the same object.

    Importing numba costs about half a second of CPU, and its first compiled call (even from
    the on-disk cache) about as much again. Classic APF, AR-APF and Wang's planners run no
    kernel, and neither does the launcher (``papf run`` checks planner names and settings
    through :mod:`nodes.planner.registry`). :data:`HAVE_NUMBA` (:mod:`common.optional`) says
    whether numba is installed without importing it.
    """
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.find_spec(name)
    if spec is None or spec.loader is None:
        raise ImportError(f"no module named {name!r}")
    spec.loader = importlib.util.LazyLoader(spec.loader)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    parent, _, child = name.rpartition(".")
    if parent:
        setattr(importlib.import_module(parent), child, module)
    return module


def numba_module() -> ModuleType:
    """numba itself (imported now, if not yet); ImportError when it is not installed."""
    return importlib.import_module("numba")


def numba_without_scipy() -> None:
    """Keep numba from importing scipy in this process (a planner node's, before its planner is built).

    numba's first compiled call imports ``numba.np.arraymath``, which imports ``scipy.linalg``
    (about 0.3 s of CPU) only to learn whether BLAS is there for ``np.dot`` and
    ``np.linalg`` inside compiled code. No planner kernel uses them (the numpy steps that
    must keep BLAS's rounding run outside the kernels, nodes/planner/papf/compiled.py), so in
    a process that has not imported scipy yet, scipy is marked missing: numba then leaves
    its BLAS functions out. ``tests/unit/test_lazy_numba.py`` builds every planner this way and
    checks its commands against a process with scipy.
    """
    if "scipy" not in sys.modules:
        sys.modules["scipy"] = None   # `import scipy` raises ImportError, numba's BLAS check says no
