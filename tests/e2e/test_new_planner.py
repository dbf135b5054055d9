"""``papf new planner``: in a copy of the repository, scaffold ``demoplanner`` from APF; only its
folder and its test appear, ``papf plan`` and ``papf run`` (real node processes) take it and
reach the goal, ``papf run --help`` lists it, its own test passes; bad names and a second
scaffold are refused in one line with exit 2 and change nothing."""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.support import warm
from tests.support.checkout import REPO, copy_checkout, tree


@pytest.fixture(scope="module")
def copy(tmp_path_factory) -> Path:
    """A copy of the checkout: the scaffold writes there, never into the repository."""
    dst = tmp_path_factory.mktemp("repo") / "papf-stack"
    copy_checkout(dst)
    return dst


def papf(copy: Path, *args: str, timeout: float = 300.0) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(copy)}   # the copy's packages before the installed ones
    return warm.run([sys.executable, "-m", "papf", *args], timeout=timeout, cwd=copy, env=env)


def test_scaffold_plan_run_help(copy):
    before = tree(copy)
    r = papf(copy, "new", "planner", "demoplanner", "--from", "apf")
    assert r.returncode == 0, r.stderr
    after = tree(copy)
    added = set(after) - set(before)
    assert {p for p in added if not p.startswith("nodes/planner/demoplanner/")} == {
        "tests/unit/test_planner_demoplanner.py"}
    assert {"nodes/planner/demoplanner/__init__.py", "nodes/planner/demoplanner/strategy.py"} <= added
    assert {p: after[p] for p in before} == before      # nothing else changed
    assert not (REPO / "nodes" / "planner" / "demoplanner").exists()

    again = papf(copy, "new", "planner", "demoplanner")        # never overwritten
    assert again.returncode == 2 and "exists already" in again.stderr
    assert tree(copy) == after

    r = papf(copy, "plan", "--world", "open", "--planner", "demoplanner", "--json")
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout)["outcome"] == "reached"

    r = papf(copy, "run", "--world", "open", "--planner", "demoplanner", "--json", timeout=600)
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout.splitlines()[-1])["outcome"] == "reached"

    r = papf(copy, "run", "--help")
    assert "demoplanner" in r.stdout

    env = {**os.environ, "PYTHONPATH": str(copy)}
    t = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
                        "tests/unit/test_planner_demoplanner.py"], cwd=copy, env=env,
                       capture_output=True, text=True, timeout=300)
    assert t.returncode == 0, t.stdout[-2000:]


@pytest.mark.parametrize("args, says", [
    (("apf",), "exists already"),
    (("core",), "exists already"),                   # a module of the planner node
    (("Bad-Name",), "lowercase"),
    (("class",), "lowercase"),                       # a Python keyword
    (("other", "--from", "nope"), "no such planner"),
])
def test_refused_in_one_line(copy, args, says):
    before = tree(copy)
    r = papf(copy, "new", "planner", *args)
    assert r.returncode == 2 and r.stdout == ""
    assert len(r.stderr.strip().splitlines()) == 1 and says in r.stderr
    assert tree(copy) == before
