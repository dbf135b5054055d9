"""numba loads only in a process whose planner runs kernels (nodes/planner/lazy.py).

The launcher (``papf run`` checks planners through the registry) and the planner node
with APF, AR-APF or Wang import no numba; a PAPF or IAPF planner does, and its scan view
is compiled too. The scan view gives the same values either way (tests/unit/test_papf_kernel.py).
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from nodes.planner import lazy


def _modules_after(code: str) -> dict:
    out = subprocess.run([sys.executable, "-c", code + "\nimport sys, json\n"
                          "print(json.dumps({m: m in sys.modules for m in ('numba', 'scipy')}))"],
                         capture_output=True, text=True, check=True, timeout=120)
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_launcher_imports_no_numba():
    assert _modules_after("import papf.cli, papf.launch.run, papf.launch.preflight, nodes.planner.registry, "
                          "nodes.planner.settings") == {"numba": False, "scipy": False}


@pytest.mark.parametrize("name", ["apf", "arapf", "wang", "wang-apf"])
def test_planner_without_kernels_runs_without_numba(name):
    code = f"""
import math, numpy as np
from nodes.planner.registry import make_planner
from schemas.messages import Goal, Odometry, Scan
p = make_planner({name!r})
p.warm_up()
assert not p.jit_scan
p.set_goal(Goal(stamp_ns=0, x=3.0, y=0.0, tolerance=0.1))
ranges = np.full(300, np.inf, np.float32)
ranges[140:160] = 1.0
scan = Scan(stamp_ns=100, angle_min=-math.pi, angle_increment=2 * math.pi / 300, range_min=0.1,
            range_max=8.0, ranges=ranges)
twist, _ = p.command(scan, Odometry(stamp_ns=100, x=0.0, y=0.0, yaw=0.0, v=0.0, w=0.0))
assert twist.stamp_ns == 100 and math.isfinite(twist.v)
"""
    assert _modules_after(code)["numba"] is False


@pytest.mark.skipif(not lazy.HAVE_NUMBA, reason="numba not installed")
@pytest.mark.parametrize("name", ["papf", "iapf"])
def test_planner_with_kernels_loads_numba_and_compiles_the_scan_view(name):
    code = f"""
from nodes.planner.registry import make_planner
p = make_planner({name!r})
assert p.jit_scan
p.warm_up()
"""
    assert _modules_after(code)["numba"] is True


def test_lazy_module_runs_on_first_attribute_and_is_the_imported_module():
    code = """
import sys
from nodes.planner.lazy import lazy_module
m = lazy_module("nodes.planner.papf.kernels")
assert "numba" not in sys.modules          # bound, not run
assert m.HAVE_NUMBA in (True, False)       # first attribute: runs it
import nodes.planner.papf.kernels as again
assert again is m and again.rollout is m.rollout
"""
    _modules_after(code)


def test_lazy_module_of_an_unknown_name_fails():
    with pytest.raises(ImportError):
        lazy.lazy_module("nodes.planner.no_such_module")


_COMMANDS = """
import json, math, sys
import numpy as np
{prelude}
from nodes.planner.registry import PLANNERS, make_planner
from tests.support.toysim import cast_scan, toy_world
from schemas.messages import Goal, Odometry
world = toy_world(circles=((1.5, 0.2, 0.3), (2.5, -0.4, 0.25)))
out = {{}}
for name in [n for n, c in PLANNERS.items() if not getattr(c, "needs_blas", False)]:   # the node hides scipy for these
    p = make_planner(name)
    p.warm_up()
    p.set_goal(Goal(stamp_ns=0, x=4.0, y=0.0, tolerance=0.1))
    x, y, yaw, cmds = 0.0, 0.0, 0.0, []
    for k in range(1, 30):   # a short drive on the commands (unicycle), each command kept
        t = k * 100_000_000
        odom = Odometry(stamp_ns=t, x=x, y=y, yaw=yaw, v=0.0, w=0.0)
        twist, _ = p.command(cast_scan(world, x, y, yaw, stamp_ns=t), odom)
        cmds.append([twist.v.hex(), twist.w.hex()])
        x, y, yaw = x + 0.1 * twist.v * math.cos(yaw), y + 0.1 * twist.v * math.sin(yaw), yaw + 0.1 * twist.w
    out[name] = cmds
print(json.dumps({{"scipy": "scipy" in sys.modules and sys.modules["scipy"] is not None, "out": out}}))
"""


@pytest.mark.skipif(not lazy.HAVE_NUMBA, reason="numba not installed")
def test_planners_without_scipy_give_the_same_commands():
    def run(prelude):
        out = subprocess.run([sys.executable, "-c", _COMMANDS.format(prelude=prelude)],
                             capture_output=True, text=True, timeout=300)
        assert out.returncode == 0, out.stderr[-2000:]
        return json.loads(out.stdout.strip().splitlines()[-1])
    hidden = run("from nodes.planner import lazy\nlazy.numba_without_scipy()")
    plain = run("import scipy.linalg")
    assert hidden["scipy"] is False and plain["scipy"] is True
    assert hidden["out"] == plain["out"]
    assert len({tuple(c) for c in hidden["out"]["papf"]}) > 10   # PAPF's kernels at work
