"""papf goal X Y on a session started by papf launch: the running planner takes the new goal."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time

import pytest

from papf.launch.supervisor import free_port, wait_port
from tests.support import warm
from tests.support.cli import papf


@pytest.mark.slow   # the slow tier (make test-quick leaves it out)
def test_goal_retargets_the_planner_of_a_launched_session():
    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    launch = warm.popen([sys.executable, "-m", "papf", "launch", "sim", "--world", "open",
                         "--planner", "papf", "--realtime", "--listen", endpoint, "--json"],
                        stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    lines: list[str] = []
    threading.Thread(target=lambda: lines.extend(launch.stderr), daemon=True).start()
    try:
        assert wait_port(port, 60.0), "the launch's router did not come up"
        deadline = time.monotonic() + 90.0      # the launch's own goal first, then ours
        while not any("papf on open" in x for x in lines):
            assert time.monotonic() < deadline and launch.poll() is None, "".join(lines)
            time.sleep(0.1)
        goal = papf("goal", "1.5", "1.0", "--connect", endpoint, "--timeout", "150", timeout=240)
        assert goal.returncode == 0, goal.stderr
        assert "acknowledged" in goal.stdout and "reached" in goal.stdout
        launch.wait(timeout=120)
        out = launch.stdout.read()
        result = json.loads(out.strip().splitlines()[-1])
        # the run ended where papf goal sent the robot, not at the world's goal (5, 0)
        assert result["outcome"] == "reached" and result["path_length_m"] < 4.0
    finally:
        if launch.poll() is None:
            os.killpg(launch.pid, signal.SIGINT)
            time.sleep(3)
            if launch.poll() is None:
                os.killpg(launch.pid, signal.SIGKILL)
            launch.wait()
