"""Issue 20, item 2 with real node processes: a planner started with a run key changes its
settings only for the viewer and `papf param set` of the user who holds that key."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from bench.foxglove_ws import FoxgloveClient
from common import runauth
from common.transport import wait_alive
from papf.launch.supervisor import free_port
from schemas import Keys

KEYS = Keys("rosbot")


def _papf(*args, env=None):
    return subprocess.run([sys.executable, "-m", "papf", *args], capture_output=True, text=True,
                          timeout=120, stdin=subprocess.DEVNULL, env=env)


@pytest.mark.slow   # the slow tier: make test-slow (CI's second step)
def test_a_keyed_planner_takes_changes_only_from_its_key(router, spawn, session, tmp_path,
                                                         monkeypatch):
    key = runauth.new_key()
    spawn("planner", [sys.executable, "-m", "nodes.planner", "--planner", "papf", "--connect",
                      router], env={runauth.ENV: key})
    assert not wait_alive(session, KEYS, ["planner"], 60.0)
    env = {**os.environ, "XDG_RUNTIME_DIR": str(tmp_path)}   # no key file: a stranger
    p = _papf("param", "set", "planner", "v_max", "0.3", "--connect", router, env=env)
    assert p.returncode == 2 and "not signed" in p.stderr, p.stderr
    p = _papf("param", "set", "planner", "d_o", "1e-9", "--connect", router, env=env)
    assert p.returncode == 2 and "[0.25, 25]" in p.stderr        # refused before sending
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    runauth.publish_key("rosbot", key)                             # as papf launch does
    p = _papf("param", "set", "planner", "v_max", "0.3", "--connect", router, env=env)
    assert p.returncode == 0 and p.stdout.strip() == "apf.v_max = 0.3", p.stderr
    p = _papf("param", "get", "planner", "apf.v_max", "--connect", router, "--json", env=env)
    assert '"apf.v_max": 0.3' in p.stdout

    for viewer_env, expect in (({}, 0.3), ({runauth.ENV: key}, 0.25)):
        port = free_port()
        spawn("viewer", [sys.executable, "-m", "nodes.viewer", "--connect", router, "--port",
                         str(port), "--world", "open"], env=viewer_env)
        client = FoxgloveClient(f"ws://127.0.0.1:{port}", timeout_s=30.0)
        try:
            assert client.wait_for(lambda c=client: "/log" in c.topics(), 30.0)
            client.request({"op": "setParameters",
                            "parameters": [{"name": "apf.v_max", "value": 0.25}]},
                           "parameterValues")
        finally:
            client.close()
        p = _papf("param", "get", "planner", "v_max", "--connect", router, env=env)
        assert p.stdout.strip() == f"apf.v_max = {expect}", (viewer_env, p.stdout, p.stderr)
