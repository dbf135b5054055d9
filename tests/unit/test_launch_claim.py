"""One launch per namespace (papf/launch/claim.py): a second launch that would start a node a
running launch has is refused with one line; other namespaces and other nodes are free."""

from __future__ import annotations

import subprocess
import sys

import pytest

from common.errors import ConfigError
from papf.launch.claim import Claim, lock_path


@pytest.fixture(autouse=True)
def runtime_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))


def test_a_second_claim_of_a_node_is_refused_until_the_first_ends():
    with Claim("rosbot", "robot", ["base_driver", "lidar_sim"]):
        with pytest.raises(ConfigError) as exc:
            with Claim("rosbot", "hil-robot", ["base_driver"]):
                pass
        text = str(exc.value)
        assert "namespace 'rosbot' is in use on this host: base_driver" in text
        assert "papf launch robot" in text and "--namespace" in text and "\n" not in text
        with Claim("rosbot", "laptop", ["planner", "energy_meter"]):   # robot + laptop: one host
            pass
        with Claim("lab/r2", "robot", ["base_driver", "lidar_sim"]):    # another namespace
            pass
    with Claim("rosbot", "hil-robot", ["base_driver"]):                # the first one ended
        pass


def test_a_dead_launchers_lock_is_free(tmp_path):
    """The kernel drops a flock with its process: a killed launch blocks nothing."""
    code = ("from papf.launch.claim import Claim; import os\n"
            "c = Claim('rosbot', 'robot', ['base_driver']).__enter__(); os._exit(0)")
    subprocess.run([sys.executable, "-c", code], check=True, timeout=60)
    assert lock_path("rosbot", "base_driver").exists()
    with Claim("rosbot", "robot", ["base_driver"]):
        pass


def test_a_refused_claim_keeps_none_of_its_nodes():
    with Claim("rosbot", "laptop", ["planner"]):
        with pytest.raises(ConfigError):
            Claim("rosbot", "sim", ["energy_meter", "planner"]).__enter__()
        with Claim("rosbot", "x", ["energy_meter"]):   # not left held by the refused claim
            pass
