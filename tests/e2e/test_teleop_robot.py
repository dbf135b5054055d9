"""papf teleop in a pseudo-terminal, through the real-robot driver, to the emulated ROSbot.

The path of a first drive (docs/getting-started-robot.md): keys -> ``rosbot/cmd_vel`` ->
``nodes.base_driver --driver rosbot`` (limits, watchdog) -> the bridge's CDR ``cmd_vel``
-> ``papf rosbot-emulator`` (which logs every command it receives with ``--trace``).
Killing the teleop outright must leave the robot stopped by the driver's watchdog.
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import threading
import time

import pytest

from common.transport import wait_alive
from schemas import Keys


def _trace(path) -> list[dict]:
    try:
        # complete lines only: the emulator may be writing the last one
        return [json.loads(x) for x in path.read_text().split("\n")[:-1] if x.strip()]
    except (OSError, json.JSONDecodeError):
        return []


def _wait(cond, what: str, timeout_s: float = 20.0) -> None:
    deadline = time.monotonic() + timeout_s
    while not cond():
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.05)


def _drain(fd: int, sink: list[bytes]) -> None:
    while True:
        try:
            data = os.read(fd, 4096)
        except OSError:
            return
        if not data:
            return
        sink.append(data)


def _shown_x(screen: list[bytes]) -> float:
    """The x [m] of the last complete ``odom x +0.12 y`` pose line on the teleop's screen."""
    found = re.findall(rb"odom x ([+-]\d+\.\d+) y", b"".join(screen))
    return float(found[-1]) if found else float("nan")


def test_teleop_drives_through_the_driver_and_the_watchdog_stops_a_killed_teleop(
        router, session, spawn, tmp_path):
    trace = tmp_path / "commands.jsonl"
    spawn("emulator", [sys.executable, "-m", "papf", "rosbot-emulator", "--connect", router,
                       "--trace", str(trace)])
    spawn("base_driver", [sys.executable, "-m", "nodes.base_driver", "--driver", "rosbot",
                          "--connect", router])
    assert not wait_alive(session, Keys(), ["rosbot_emulator", "base_driver"], 60.0)
    master, slave = os.openpty()
    teleop = subprocess.Popen([sys.executable, "-m", "papf", "teleop", "--connect", router],
                              stdin=slave, stdout=slave, stderr=slave, start_new_session=True)
    os.close(slave)
    screen: list[bytes] = []
    threading.Thread(target=_drain, args=(master, screen), daemon=True).start()
    try:
        _wait(lambda: b"papf teleop on rosbot/cmd_vel" in b"".join(screen), "teleop banner")
        os.write(master, b"ww")
        _wait(lambda: any(c["v"] == pytest.approx(0.1) for c in _trace(trace)), "v = 0.1 at the robot")
        # no run started: the driver still publishes odometry, so the pose line shows it
        _wait(lambda: _shown_x(screen) > 0.01, "the robot moving in the odometry on screen")
        os.write(master, b"\x1b[C")                  # right arrow: turn clockwise
        _wait(lambda: _trace(trace)[-1]["w"] < 0, "w < 0 at the robot")
        os.kill(teleop.pid, signal.SIGKILL)          # no goodbye zeros: only the watchdog
        teleop.wait(10)
        killed_ns = time.monotonic_ns()
        _wait(lambda: (lambda c: c and c[-1]["v"] == 0.0 and c[-1]["w"] == 0.0)(_trace(trace)),
              f"the driver's watchdog stop; last commands {_trace(trace)[-3:]}")
        stop = next(c for c in _trace(trace) if c["t_ns"] > killed_ns and c["v"] == 0.0)
        # 0.5 s watchdog, then the controller's deceleration limit (1 m/s^2 from 0.1 m/s)
        assert (stop["t_ns"] - killed_ns) * 1e-9 < 2.0
    finally:
        if teleop.poll() is None:
            os.killpg(teleop.pid, signal.SIGKILL)
            teleop.wait()
        os.close(master)
