"""pysocialforce's numba kernels are cached on disk (common/crowd.py ``_cache_kernels``): a
process after the first loads them instead of compiling them again (about 5 s of CPU)."""

from __future__ import annotations

import json
import subprocess
import sys
import types

import pytest

numba = pytest.importorskip("numba")

from common.crowd import _cache_kernels, load_pysocialforce  # noqa: E402

CHILD = """
import json
from nodes.planner.registry import make_planner
make_planner("social_force").warm_up()
from pysocialforce.utils import stateutils
ds = [d for d in vars(stateutils).values() if hasattr(d, "stats")]
print(json.dumps({"hits": sum(sum(d.stats.cache_hits.values()) for d in ds),
                  "misses": sum(sum(d.stats.cache_misses.values()) for d in ds)}))
"""


def test_only_kernels_that_compiled_nothing_yet_are_turned_on():
    mod = types.ModuleType("toy")
    mod.fresh = numba.njit(lambda x: x + 1)
    mod.used = numba.njit(lambda x: x * 2)
    mod.used(3)                                  # compiled already: left as it is
    mod.plain = lambda x: x
    assert _cache_kernels(mod) == 1
    assert type(mod.fresh._cache).__name__ == "FunctionCache"
    assert type(mod.used._cache).__name__ == "NullCache"


def test_a_kernel_numba_cannot_cache_stays_uncached_and_still_runs():
    class NoLocator:                             # as numba where no cache dir is writable
        signatures = ()

        def enable_caching(self):
            raise RuntimeError("cannot cache function 'f': no locator available for file 'f.py'")

    mod = types.ModuleType("toy")
    mod.ro = NoLocator()
    mod.fresh = numba.njit(lambda x: x + 1)
    assert _cache_kernels(mod) == 1 and mod.fresh(1) == 2


def test_every_pysocialforce_kernel_has_its_cache_on():
    load_pysocialforce()
    from pysocialforce.utils import stateutils
    kernels = [d for d in vars(stateutils).values() if hasattr(d, "enable_caching")]
    assert len(kernels) >= 5
    assert all(type(d._cache).__name__ == "FunctionCache" for d in kernels)


def test_a_second_process_loads_the_kernels_instead_of_compiling_them():
    from nodes.planner.registry import make_planner
    make_planner("social_force").warm_up()       # compiled into the cache here if not there yet
    out = subprocess.run([sys.executable, "-c", CHILD], capture_output=True, text=True,
                         check=True).stdout
    counts = json.loads(out.strip().splitlines()[-1])
    assert counts["hits"] > 0 and counts["misses"] == 0, counts
