"""The robot/laptop split in the link tests (tests/e2e/test_link_*.py): a corridor world, one
``papf run --link`` as a process, and the robot's command trace read back."""

from __future__ import annotations

import json
from pathlib import Path

from tests.support.cli import papf
from tests.support.worlds import box_world

CORRIDOR = box_world("corridor", "2.5 m ahead, a box beside the path", 2.5, (1.2, 0.7))
RUN_TIMEOUT_S = 300                # [s wall] one split run, start-up on a loaded machine included


def split_run(world: Path, ns: str, link: str, *extra: str) -> tuple[int, dict, str]:
    """``papf run --link LINK --json``: exit code, JSON, stderr."""
    out = papf("run", "--world", world, "--planner", "apf", "--namespace", ns, "--link", link,
               "--json", "--timeout", "60", *extra, timeout=RUN_TIMEOUT_S)
    assert out.stdout.strip(), out.stderr[-3000:]
    return out.returncode, json.loads(out.stdout.strip().splitlines()[-1]), out.stderr


def commands(trace: Path) -> list[dict]:
    """The commands of a driver's ``--trace`` file, one JSON object a line (a cut last line skipped)."""
    return [json.loads(line) for line in trace.read_text().splitlines() if line.endswith("}")]
