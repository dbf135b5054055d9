"""A copy of the checkout for a test that writes into it (``papf new planner``)."""

from __future__ import annotations

import hashlib
import shutil
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
NOT_COPIED = {".git", ".venv", ".pytest_cache", ".ruff_cache", ".hypothesis"}
CACHES = NOT_COPIED | {"__pycache__"}   # what tree() leaves out


def copy_checkout(dst: Path) -> Path:
    """The checkout copied to ``dst``, with its bytecode: the sources keep their times, so
    it stays valid (a file the test writes is compiled again). Without it, where
    PYTHONDONTWRITEBYTECODE is set, every process started in the copy compiled every module
    it imports from source."""
    shutil.copytree(REPO, dst, ignore=lambda _dir, names: [
        n for n in names if n in NOT_COPIED or n.endswith(".egg-info")])
    return dst


def tree(root: Path) -> dict[str, str]:
    """Relative path -> sha256 of every file under ``root`` (caches left out)."""
    return {str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in root.rglob("*")
            if p.is_file() and not CACHES.intersection(p.relative_to(root).parts)}
