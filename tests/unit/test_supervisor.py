"""The supervisor's node command lines (papf/launch/supervisor.py): a node started from a
directory holding our package names imports ours."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from papf.launch.supervisor import _SAFE_BOOT, safe_argv


def _shadow(tmp_path: Path) -> Path:
    (tmp_path / "worlds").mkdir()
    (tmp_path / "worlds" / "__init__.py").write_text("")
    (tmp_path / "common").mkdir()
    (tmp_path / "common" / "__init__.py").write_text("raise SystemExit('shadowed')\n")
    return tmp_path


def test_nodes_started_from_a_directory_with_our_package_names_import_ours(tmp_path):
    import os

    cwd = _shadow(tmp_path)
    argv = safe_argv([sys.executable, "-m", "nodes.recorder", "--help"])
    env = {**os.environ, "PYTHONSAFEPATH": "1"}
    p = subprocess.run(argv, cwd=cwd, env=env, capture_output=True, text=True, timeout=120)
    assert p.returncode == 0 and "shadowed" not in p.stdout + p.stderr
    boot = [sys.executable, "-c", _SAFE_BOOT, "nodes.recorder", "--help"]   # the 3.10 path
    p = subprocess.run(boot, cwd=cwd, capture_output=True, text=True, timeout=120)
    assert p.returncode == 0 and "usage: python -m nodes.recorder" in p.stdout
