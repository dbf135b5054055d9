"""A new planner's debug output appears everywhere with no file outside its folder touched:
in a copy of the checkout, ``papf new planner`` scaffolds ``probe`` from APF, its strategy
(in its folder only) declares a points field and a scalar and returns them; its
``PlannerState`` carries them, the viewer's scene, the ROS 2 face's markers and
``papf plan --plot`` draw them in its declared style."""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.support.checkout import copy_checkout, tree

STRATEGY = Path("nodes/planner/probe/strategy.py")

DECLARE = '''
    DEBUG = (DebugField("probe_marks", "points", unit="m", label="probe mark",
                        style=Style((0.0, 0.8, 0.2, 1.0), 0.3)),
             DebugField("probe_gain", "scalar", unit="1/s"))
'''
RETURN = '''        force = apf_force(pos, goal, view.points, apf)
        return Plan(force=force, debug={"probe_marks": [pos + (0.5, 0.0), pos + (0.0, 0.5)],
                                        "probe_gain": 0.25})
'''

SHOW = '''
import json, math
import numpy as np
import matplotlib.pyplot as plt
from common import ros2_convert
from nodes.planner.registry import make_planner
from nodes.viewer.scene import mind_scene
from papf.plots.mind import draw_mind
from schemas.messages import Goal, Odometry, PlannerState, Scan

planner = make_planner("probe")
planner.set_goal(Goal(stamp_ns=0, x=3.0, y=0.0))
scan = Scan(stamp_ns=1, angle_min=0.0, angle_increment=0.4, range_min=0.2, range_max=10.0,
            ranges=np.full(16, np.inf, np.float32))
_, state, _ = planner.step(scan, Odometry(stamp_ns=1, x=1.0, y=2.0, yaw=0.0, v=0.0, w=0.0))
state = PlannerState.from_bytes(state.to_bytes())          # as on the bus
scene = mind_scene(state, (1.0, 2.0))["entities"][0]
markers = ros2_convert.markers(state, robot_xy=(1.0, 2.0)).markers
ax = plt.figure().add_subplot()
draw_mind(ax, state)
print(json.dumps({
    "debug": [[d.name, d.kind, d.unit, list(d.colour), d.size, [list(p) for p in d.points],
               None if math.isnan(d.value) else d.value] for d in state.debug],
    "spheres": [[s["pose"]["position"]["x"], s["pose"]["position"]["y"], s["size"]["x"],
                 s["color"]["g"]] for s in scene["spheres"]],
    "caption": scene["texts"][0]["text"],
    "markers": [[m.ns, m.type, [[p.x, p.y] for p in m.points], m.text] for m in markers],
    "legend": [t.get_text() for t in ax.legend().get_texts()],
}))
'''


def run(copy: Path, *argv: str, timeout: float = 300.0) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(copy)}   # the copy's packages before the installed ones
    return subprocess.run([sys.executable, *argv], cwd=copy, env=env, text=True,
                          capture_output=True, timeout=timeout)


@pytest.fixture(scope="module")
def copy(tmp_path_factory) -> Path:
    """A copy of the checkout with ``probe`` scaffolded and given debug output in its folder."""
    dst = tmp_path_factory.mktemp("repo") / "papf-stack"
    copy_checkout(dst)
    before = tree(dst)
    r = run(dst, "-m", "papf", "new", "planner", "probe", "--from", "apf")
    assert r.returncode == 0, r.stderr
    source = (dst / STRATEGY).read_text(encoding="utf-8")
    body = "        return Plan(force=apf_force(pos, goal, view.points, apf))\n"
    assert body in source and "    def plan(" in source
    source = source.replace(body, RETURN).replace("    def plan(", DECLARE + "\n    def plan(", 1)
    source = source.replace("from nodes.planner.core import",
                            "from nodes.planner.debug import DebugField, Style\n"
                            "from nodes.planner.core import", 1)
    (dst / STRATEGY).write_text(source, encoding="utf-8")
    after = tree(dst)
    changed = {p for p in after if before.get(p) != after[p]} | (set(before) - set(after))
    assert {p for p in changed if not p.startswith("nodes/planner/probe/")} == {
        "tests/unit/test_planner_probe.py"}
    return dst


def test_its_debug_output_is_in_the_message_the_scene_and_the_markers(copy):
    r = run(copy, "-c", SHOW)
    assert r.returncode == 0, r.stderr
    got = json.loads(r.stdout)
    assert got["debug"] == [
        ["probe_marks", "points", "m", [0.0, 0.8, 0.2, 1.0], 0.3, [[1.5, 2.0], [1.0, 2.5]], None],
        ["probe_gain", "scalar", "1/s", [0.5, 0.5, 0.5, 1.0], 0.05, [], 0.25]]
    assert [1.5, 2.0, 0.3, 0.8] in got["spheres"] and [1.0, 2.5, 0.3, 0.8] in got["spheres"]
    assert got["caption"] == "probe: drive · probe gain 0.25 1/s"
    by_ns = {m[0]: m for m in got["markers"]}
    assert by_ns["mind/probe_marks"][2] == [[1.5, 2.0], [1.0, 2.5]]
    assert by_ns["mind/probe_gain"][3] == "probe gain 0.25 1/s"
    assert "probe mark" in got["legend"]


def test_papf_plan_draws_it_and_its_own_test_passes(copy, tmp_path):
    png = tmp_path / "probe.png"
    r = run(copy, "-m", "papf", "plan", "--world", "open", "--planner", "probe", "--json",
            "--plot", str(png))
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout)["outcome"] == "reached" and png.stat().st_size > 10_000
    t = run(copy, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-p", "no:randomly",
            "tests/unit/test_planner_probe.py", "tests/unit/test_planner_debug.py")
    assert t.returncode == 0, t.stdout[-2000:]
