"""The rosbot driver refuses a bridge namespace overlapping ours (with a router on loopback)."""

from __future__ import annotations

import subprocess
import sys


def test_bridge_namespace_overlap_is_refused(router):
    proc = subprocess.run([sys.executable, "-m", "nodes.base_driver", "--driver", "rosbot",
                           "--connect", router, "--bridge-namespace", "rosbot"],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2 and "overlaps our namespace" in proc.stderr
