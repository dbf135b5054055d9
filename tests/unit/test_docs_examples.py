"""Every command example of README.md and docs/ is valid today (papf/doctools/examples.py).

The papf ones parse with the real parser (a renamed option or command fails here first);
a ``python -m`` one names a module that exists; a ``make`` one a target of the Makefile;
any other program is one of :data:`OTHER_TOOLS`, with the reason the e2e test
(tests/e2e/test_docs_examples.py) cannot run it here.
"""

from __future__ import annotations

import contextlib
import importlib.util
import io
import re

import pytest

from papf.cli import build_parser
from papf.doctools.examples import ROOT, Example, concrete, examples, papf_argv

OTHER_TOOLS = {
    "ros2": "the robot's ROS 2 install",
    "zenoh-bridge-ros2dds": "a binary of the robot host (docs/getting-started-robot.md)",
    "git": "the repository's own history and clones",
    "sudo": "installs system packages",
    "scp": "copies to the robot",
    "dask": "run: tests/e2e/test_docs_examples.py starts the scheduler and a worker here",
    "pip": "installs this project (make setup does it here)",
}
EXAMPLES = examples()


def _id(ex: Example) -> str:
    return ex.where


def test_the_docs_have_examples():
    files = {ex.file for ex in EXAMPLES}
    assert "README.md" in files and len(EXAMPLES) > 80, files


@pytest.mark.parametrize("ex", [e for e in EXAMPLES if papf_argv(e) is not None], ids=_id)
def test_papf_example_parses(ex):
    argv = papf_argv(ex)
    if argv == ["--help"]:
        return
    err = io.StringIO()
    try:
        with contextlib.redirect_stderr(err):
            build_parser().parse_args(argv)
    except SystemExit as stop:
        pytest.fail(f"{ex.where}: {ex.text!r} does not parse (exit {stop.code}): "
                    f"{err.getvalue().strip()}")


@pytest.mark.parametrize("ex", [e for e in EXAMPLES if papf_argv(e) is None], ids=_id)
def test_other_example_is_known(ex):
    argv = concrete(ex)
    name = argv[0].rsplit("/", 1)[-1]
    if name in ("python", "python3") and argv[1] == "-m" and argv[2] != "venv":
        assert importlib.util.find_spec(argv[2]) is not None, f"{ex.where}: no module {argv[2]}"
    elif name == "make":
        targets = re.findall(r"^([a-z-]+):", (ROOT / "Makefile").read_text(), re.M)
        assert argv[1] in targets, f"{ex.where}: no Makefile target {argv[1]!r}"
    else:
        tool = "pip" if name in ("python3", "python") else name
        assert tool in OTHER_TOOLS, (f"{ex.where}: {ex.text!r}: a program the docs tests do not "
                                     "know; run it in tests/e2e/test_docs_examples.py or name it "
                                     "in OTHER_TOOLS with the reason it cannot run")
