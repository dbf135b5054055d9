"""Issue 30 item 4: a laptop SIGKILLed mid-run and started again, over two routers (the robot's
and the laptop's, joined through ``papf link --profile wifi``), against the ROSbot emulator.

No node of the killed laptop outlives it; the next launch refuses to guess (exit 2, one line)
and then does what it is told: ``--new-run`` drives from where the robot stands with a fresh
clock, meter and recording (the robot never re-drives the course), ``--resume`` goes on with
the same run (its id, charge and path)."""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import zenoh

from common.transport import zenoh_config
from papf.launch.supervisor import free_port, wait_port
from papf.recording.reader import iter_messages, read_metadata
from schemas import Keys, Odometry
from tests.support import warm
from tests.support.worlds import FAST, box_world, write_world

PY = sys.executable
GOAL_X = 3.0          # [m] straight ahead; killed past KILL_X
KILL_X = 0.8          # [m]
LAPTOP_NODES = ("nodes.planner", "nodes.energy_meter", "nodes.recorder")


def _cmdlines(tag: str, with_pid: bool = False) -> list:
    out = []
    for pid in filter(str.isdigit, os.listdir("/proc")):
        try:
            cmd = Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode()
            state = Path(f"/proc/{pid}/stat").read_text().split()[2]
        except OSError:
            continue
        if tag in cmd and state != "Z" and int(pid) != os.getpid():
            out.append((int(pid), cmd) if with_pid else cmd)
    return out


def _describe(pid: int) -> str:
    """A process that should be gone, as /proc sees it: its parent, and each thread's name,
    state and kernel wait channel (where a stuck stop is stuck)."""
    try:
        ppid = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[1]
        threads = []
        for tid in sorted(os.listdir(f"/proc/{pid}/task")):
            task = Path(f"/proc/{pid}/task/{tid}")
            comm = (task / "comm").read_text().strip()
            state = (task / "stat").read_text().rsplit(")", 1)[1].split()[0]
            threads.append(f"{comm}:{state}:{(task / 'wchan').read_text().strip()}")
    except OSError as exc:
        return f"{pid}: {exc}"
    return f"{pid} (parent {ppid}): {' '.join(threads)}"


def _laptop_nodes(ns: str, endpoint: str) -> list[str]:
    return [c for c in _cmdlines(endpoint) if ns in c and any(m in c for m in LAPTOP_NODES)]


class Split:
    """The robot side (its router, the rosbot driver, the emulator) and the laptop's router."""

    def __init__(self, tmp: Path, ns: str):
        self.ns, self.tmp = ns, tmp
        self.world = str(write_world(tmp / "line.toml", box_world("line", "3 m ahead", GOAL_X,
                                                                    (1.5, 1.0))))
        self.robot_ep = f"tcp/127.0.0.1:{free_port()}"
        self.laptop_ep = f"tcp/127.0.0.1:{free_port()}"
        self.link_ep = f"tcp/127.0.0.1:{free_port()}"
        self.procs: list[subprocess.Popen] = []

    def start(self) -> None:
        self._spawn(["launch", "robot", "--listen", self.robot_ep, "--namespace", self.ns,
                     "--world", self.world], "robot")
        assert wait_port(int(self.robot_ep.rsplit(":", 1)[1]), 30.0)
        # the laptop's router joins the robot's through the link emulator (a Wi-Fi's figures)
        self._spawn(["link", "--listen", self.link_ep, "--to", self.robot_ep, "--profile",
                     "wifi"], "link")
        assert wait_port(int(self.link_ep.rsplit(":", 1)[1]), 30.0)
        self.procs.append(subprocess.Popen(
            [PY, "-m", "papf.launch.router", "--listen", self.laptop_ep, "--join", self.link_ep],
            start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        self._spawn(["rosbot-emulator", "--connect", self.robot_ep, "--namespace", self.ns,
                     "--world", self.world], "emulator")
        assert wait_port(int(self.laptop_ep.rsplit(":", 1)[1]), 30.0)

    def _spawn(self, args: list[str], name: str) -> subprocess.Popen:
        proc = warm.popen([PY, "-m", "papf", *args], stdout=subprocess.DEVNULL,
                          stderr=(self.tmp / f"{name}.log").open("w"))
        self.procs.append(proc)
        return proc

    def laptop_args(self, record: Path, *extra: str) -> list[str]:
        return [PY, "-m", "papf", "launch", "laptop", "--connect", self.laptop_ep, "--namespace",
                self.ns, "--world", self.world, "--timeout", "60", "--json", "--record",
                str(record), *FAST, *extra]

    def stop(self) -> None:
        for proc in reversed(self.procs):
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGTERM)
        for proc in reversed(self.procs):
            try:
                proc.wait(timeout=20)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)
                proc.wait()


@pytest.fixture
def split(tmp_path):
    s = Split(tmp_path, f"t31r{os.getpid() % 10000}")
    s.start()
    yield s
    s.stop()


def _kill_laptop_mid_run(split: Split, record: Path) -> float:
    """Start a laptop run, SIGKILL its launcher once the robot is past KILL_X; the robot's x."""
    laptop = subprocess.Popen(split.laptop_args(record), start_new_session=True,
                              stdout=subprocess.PIPE, stderr=(split.tmp / "laptop1.log").open("w"))
    x = -math.inf
    keys = Keys(split.ns)
    with zenoh.open(zenoh_config("client", [split.robot_ep])) as s:
        sub = s.declare_subscriber(keys.odom, zenoh.handlers.FifoChannel(4096))
        deadline = time.monotonic() + 120
        while x < KILL_X and time.monotonic() < deadline and laptop.poll() is None:
            sample = sub.try_recv()
            if sample is None:
                time.sleep(0.02)
                continue
            x = max(x, Odometry.from_bytes(sample.payload.to_bytes()).x)
    assert x >= KILL_X, (split.tmp / "laptop1.log").read_text()[-3000:]
    os.kill(laptop.pid, signal.SIGKILL)   # the launcher only: its nodes must go by themselves
    laptop.wait()
    deadline = time.monotonic() + 15
    while _laptop_nodes(split.ns, split.laptop_ep) and time.monotonic() < deadline:
        time.sleep(0.1)
    left = [(pid, cmd) for pid, cmd in _cmdlines(split.laptop_ep, with_pid=True)
            if split.ns in cmd and any(m in cmd for m in LAPTOP_NODES)]
    assert not left, "a node outlived its launcher: " + "; ".join(
        f"{cmd.split(' -m ')[-1][:40]} {_describe(pid)}" for pid, cmd in left)
    return x


def _refused_without_a_choice(split: Split, record: Path) -> None:
    p = subprocess.run(split.laptop_args(record), capture_output=True, text=True, timeout=60)
    assert p.returncode == 2, p.stderr[-2000:]
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and "--resume" in lines[0] and "--new-run" in lines[0], p.stderr
    assert not record.exists()


def test_new_run_from_where_the_robot_stands(split, tmp_path):
    x_kill = _kill_laptop_mid_run(split, tmp_path / "first.mcap")
    _refused_without_a_choice(split, tmp_path / "second.mcap")
    second = tmp_path / "second.mcap"
    p = subprocess.run(split.laptop_args(second, "--new-run"), capture_output=True, text=True,
                       timeout=180)
    result = json.loads(p.stdout.strip().splitlines()[-1])
    assert result["outcome"] == "reached", p.stderr[-3000:]
    # from where it stood to the goal, not the course again from there
    assert result["path_length_m"] < GOAL_X - x_kill + 0.6, result
    meta = read_metadata(second)["run"]
    assert meta["run_id"] == result["run_id"]
    first_run = read_metadata_or_none(tmp_path / "first.mcap")
    assert first_run is None or first_run != result["run_id"]
    odoms = [m for _, m, _ in iter_messages(second, keys=[Keys(split.ns).odom])]
    stamps = [o.stamp_ns for o in odoms]
    assert stamps == sorted(stamps) and stamps[0] < 2_000_000_000   # one clock, from ~0
    assert abs(odoms[-1].x - GOAL_X) < 0.4 and max(o.x for o in odoms) < GOAL_X + 0.4


def test_resume_goes_on_with_the_same_run(split, tmp_path):
    _kill_laptop_mid_run(split, tmp_path / "first.mcap")
    first_run = read_metadata_or_none(tmp_path / "first.mcap")
    second = tmp_path / "second.mcap"
    p = subprocess.run(split.laptop_args(second, "--resume"), capture_output=True, text=True,
                       timeout=180)
    result = json.loads(p.stdout.strip().splitlines()[-1])
    assert result["outcome"] == "reached", p.stderr[-3000:]
    if first_run is not None:
        assert result["run_id"] == first_run
    assert result["path_length_m"] > GOAL_X - 0.5          # the whole run's path, not its tail
    batteries = [m for _, m, _ in iter_messages(second, keys=[Keys(split.ns).battery])]
    assert batteries[0].charge_used_mAh > 0.0               # the account went on


def read_metadata_or_none(path: Path) -> str | None:
    """The run id of a recording its killed launcher's recorder may or may not have closed."""
    try:
        return read_metadata(path)["run"].get("run_id")
    except Exception:
        return None
