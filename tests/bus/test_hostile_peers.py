"""Issue 31's attacks, run against a live stack (a lockstep ``papf run`` on a short world) by a
peer that holds no key: a replayed goal, a forged collision, a scan stamped 2^62 ns and
"no obstacle" scans a little ahead of the clock, a foreign Twist, a byte flood on a recorded
key, a frozen recorder.

Nothing the peer sends changes the robot's motion or the run's outcome: the attacked run's
figures are the clean run's to the last digit (lockstep is deterministic). Every drop is
counted and visible: in the run's JSON (``refused``), in the recording's summary
(``not_recorded``) and in the nodes' health answers (``papf topic list``). A frozen recorder
ends the run as failed, saying that the recording stopped early.
"""

from __future__ import annotations

import json
import os
import signal
import threading
import time

import numpy as np
import pytest
import zenoh

from common.transport import zenoh_config
from common.units import MAX_STAMP_NS
from papf.launch.supervisor import free_port, wait_port
from papf.recording.reader import iter_messages, read_metadata
from schemas import Event, Keys, Scan, Twist
from tests.support.e2e import papf_run, pids_of, start_papf_run
from tests.support.worlds import FAST, SHORT, write_world

FIGURES = ("outcome", "duration_s", "path_length_m", "charge_mAh", "energy_J", "collisions",
           "sim_time_s")
FLOOD_BYTES = 512 * 1024     # [B] a flood sample (issue 31)
KEYS = Keys()


@pytest.fixture
def world(tmp_path) -> str:
    return str(write_world(tmp_path / "short.toml", SHORT))


def _clear_scan(stamp: int) -> bytes:
    """A "no obstacle anywhere" scan (what a spoofer wants the planner to see)."""
    return Scan(stamp_ns=stamp, angle_min=-3.14159, angle_increment=0.0175, range_min=0.2,
                range_max=12.0, ranges=np.full(360, np.inf, np.float32)).to_bytes()


class Attacker:
    """A keyless client of the run's router: listens for the run, then attacks until stopped."""

    def __init__(self, endpoint: str, flood: bool = True):
        self.endpoint, self.flood = endpoint, flood
        self.stop, self.started = threading.Event(), threading.Event()
        self.sent: dict[str, int] = {}
        self.goal: tuple[bytes, bytes | None] | None = None
        self.thread = threading.Thread(target=self._run, daemon=True)

    def _count(self, what: str) -> None:
        self.sent[what] = self.sent.get(what, 0) + 1

    def _run(self) -> None:
        with zenoh.open(zenoh_config("client", [self.endpoint])) as s:
            def on_goal(sample) -> None:   # the run's own sealed goal: captured to replay
                att = sample.attachment
                self.goal = (sample.payload.to_bytes(), None if att is None else att.to_bytes())

            def on_pose(_sample) -> None:
                self.started.set()

            subs = [s.declare_subscriber(KEYS.goal, on_goal),
                    s.declare_subscriber(KEYS.key("sim/pose"), on_pose)]
            self.started.wait(120)
            big = os.urandom(FLOOD_BYTES)
            clock = 0
            while not self.stop.is_set():
                self._attack(s, big, clock)
                clock += 100_000_000
                time.sleep(0.01)
            for sub in subs:
                sub.undeclare()

    def _attack(self, s, big: bytes, clock: int) -> None:
        if self.goal is not None:                       # the goal put again, seal and all
            payload, att = self.goal
            s.put(KEYS.goal, payload, attachment=att) if att else s.put(KEYS.goal, payload)
            self._count("goal replay")
        s.put(KEYS.events, Event(stamp_ns=clock, kind="collision", source="base_driver",
                                 detail="forged", x=0.5, y=0.0).to_bytes())
        self._count("forged collision")
        s.put(KEYS.scan, _clear_scan(MAX_STAMP_NS))     # one scan from the far future...
        s.put(KEYS.scan, _clear_scan(clock + 50_000_000))   # ...and "a little ahead"
        self._count("spoofed scans")
        s.put(KEYS.cmd_vel, Twist(stamp_ns=clock, v=0.9, w=3.0).to_bytes())
        self._count("foreign twist")
        if self.flood:
            s.put(KEYS.odom, big)                        # a byte flood on a recorded key
            s.put(KEYS.key("planner/state"), big)
            self._count("flood")

    def __enter__(self) -> Attacker:
        self.thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self.stop.set()
        self.thread.join(15)


def _attacked_run(world: str, record, *, flood: bool = True) -> tuple[int, dict, str, dict]:
    port = free_port()
    args = ("--world", world, "--planner", "apf", "--timeout", "60", *FAST, "--record",
            str(record))
    proc = start_papf_run(*args, port=port)
    try:
        assert wait_port(port, 60), "the run's router never came up"
        with Attacker(f"tcp/127.0.0.1:{port}", flood) as attacker:
            out, err = proc.communicate(timeout=240)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    return proc.returncode, json.loads(out.strip().splitlines()[-1]), err, attacker.sent


def test_nothing_a_keyless_peer_sends_changes_the_run(world, tmp_path):
    code, clean, err = papf_run("--world", world, "--planner", "apf", "--timeout", "60", *FAST,
                                "--record", str(tmp_path / "clean.mcap"))
    assert code == 0 and clean["outcome"] == "reached", err[-2000:]
    code, hit, err, sent = _attacked_run(world, tmp_path / "hit.mcap")
    assert sent.get("forged collision", 0) > 10 and sent.get("flood", 0) > 5, sent
    assert code == 0, err[-3000:]
    assert {k: hit[k] for k in FIGURES} == {k: clean[k] for k in FIGURES}
    refused = hit["refused"]
    assert refused["launcher"]["events"]["unsigned"] > 0          # the forged collision
    assert refused["planner"]["scan"]["unsigned"] > 0             # 2^62 and the spoofed scans
    assert refused["base_driver"]["cmd_vel"]["unsigned"] > 0      # the foreign Twist
    assert "replay" in refused["planner"]["goal"] or sent.get("goal replay", 0) == 0
    # the recording: one run's samples, every odometry sample of the run, the drops named
    meta = read_metadata(tmp_path / "hit.mcap")
    assert meta["run"]["run_id"] == hit["run_id"]
    dropped = {k: json.loads(v) for k, v in meta["not_recorded"].items()}
    assert dropped[KEYS.odom]["unsigned"] > 0 and dropped[KEYS.events]["unsigned"] > 0
    end = round(hit["sim_time_s"] * 1e9)   # samples after t_end: as many as came before close
    odom = [m.stamp_ns for _, m, _ in iter_messages(tmp_path / "hit.mcap", keys=[KEYS.odom])
            if m.stamp_ns <= end]
    odom_clean = [m.stamp_ns for _, m, _ in iter_messages(tmp_path / "clean.mcap",
                                                           keys=[KEYS.odom]) if m.stamp_ns <= end]
    assert odom == odom_clean == list(range(0, end + 1, 20_000_000))   # every one, none twice
    assert hit["recording"]["complete"] and hit["recording"]["dropped"]


def test_a_frozen_recorder_makes_the_run_say_its_recording_stopped(world, tmp_path):
    port = free_port()
    record = tmp_path / "frozen.mcap"
    proc = start_papf_run("--world", world, "--planner", "apf", "--timeout", "60", *FAST,
                          "--record", str(record), port=port)
    frozen: list[int] = []
    try:
        assert wait_port(port, 60)
        with zenoh.open(zenoh_config("client", [f"tcp/127.0.0.1:{port}"])) as s:
            started = threading.Event()
            sub = s.declare_subscriber(KEYS.key("sim/pose"), lambda _s: started.set())
            assert started.wait(120), "the run never started"
            frozen = pids_of("nodes.recorder", port)
            assert frozen
            for pid in frozen:
                os.kill(pid, signal.SIGSTOP)
            sub.undeclare()
        out, err = proc.communicate(timeout=240)
    finally:
        for pid in frozen:
            try:
                os.kill(pid, signal.SIGCONT)
            except ProcessLookupError:
                pass
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    res = json.loads(out.strip().splitlines()[-1])
    assert proc.returncode == 6 and res["outcome"] == "failed", err[-2000:]
    assert res["reason"].startswith("the recording stopped early") and "reached" in res["reason"]
    assert res["recording"]["complete"] is False
