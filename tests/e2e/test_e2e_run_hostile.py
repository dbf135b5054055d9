"""``papf run`` (real processes, router, physics) against hostile peers and faults.

A peer that holds no key — a bounded bus fuzz, a replayed goal, a forged collision, a scan
stamped 2^62 ns and "no obstacle" scans a little ahead of the clock, a foreign Twist, a byte
flood on a recorded key — changes nothing: the attacked run's figures are the clean run's to
the last digit (lockstep is deterministic), and every drop is counted and visible (``refused``
in the run's JSON, ``not_recorded`` in the recording's summary, the nodes' health answers).
A frozen recorder, a dead meter, a full disk and a foreign router each end the run honestly.
Beside tests/e2e/test_e2e_run.py (docs/architecture.md, "Tests")."""

from __future__ import annotations

import json
import os
import signal
import sys
import threading
import time

import msgpack
import numpy as np
import pytest
import zenoh

from common.transport import zenoh_config
from common.units import MAX_STAMP_NS
from papf.launch.supervisor import Supervisor, free_port, wait_port
from papf.recording.reader import iter_messages, read_metadata
from schemas import BatteryState, Clock, Event, Goal, Keys, PlannerStatus
from schemas.keys import TOPICS
from schemas.messages import Odometry, Scan, Twist
from tests.support.cli import papf
from tests.support.e2e import assert_no_orphans, papf_run, pids_of, start_papf_run
from tests.support.worlds import FAST, SHORT, STEADY, box_world, write_world

FIGURES = ("outcome", "duration_s", "path_length_m", "charge_mAh", "energy_J", "collisions",
           "sim_time_s")


BAD_STAMPS = (-1, -2**63, 2**62 + 1, 2**63, 2**64 - 1)


FLOOD_BYTES = 512 * 1024     # [B] a flood sample (issue 31)
KEYS = Keys()


def _valid_like(msg_type, stamp: int) -> bytes:
    """A message of ``msg_type`` that is valid in every field but ``stamp_ns``."""
    samples = {
        Odometry: Odometry(stamp_ns=0, x=9.0, y=9.0, yaw=1.0, v=0.5, w=0.5),
        Scan: Scan(stamp_ns=0, angle_min=0.0, angle_increment=0.1, range_min=0.1,
                   range_max=10.0, ranges=np.full(63, 0.3, np.float32)),
        Twist: Twist(stamp_ns=0, v=0.9, w=3.0),
        Goal: Goal(stamp_ns=0, x=-5.0, y=3.0),
        PlannerStatus: PlannerStatus(stamp_ns=0, state="reached"),
        Clock: Clock(stamp_ns=0),
        Event: Event(stamp_ns=0, kind="run_ended", source="fuzz"),
    }
    msg = samples.get(msg_type)
    if msg is None:
        return b"\x80"
    wire = msg.to_wire()
    wire["stamp_ns"] = stamp
    return msgpack.packb(wire, use_bin_type=True)


def _fuzz(endpoint: str, stop: threading.Event, counts: dict) -> None:
    """Garbage, wrong types, out-of-range stamps on every topic; forged goal and reached."""
    keys = Keys()
    garbage = [b"", b"\xff\x00garbage", os.urandom(64), b"\x93\x01\x02\x03", b"\xc1" * 10]
    wrong = Twist(stamp_ns=5, v=0.5, w=0.5).to_bytes()          # a Twist where it is not one
    forged = [Goal(stamp_ns=0, x=-5.0, y=3.0).to_bytes(),       # in range, but not this run's
              PlannerStatus(stamp_ns=20_000_000, state="reached").to_bytes()]
    with zenoh.open(zenoh_config("client", [endpoint])) as s:
        i = 0
        while not stop.is_set() and i < 150:
            for topic, msg_type in TOPICS.items():
                key = keys.key(topic)
                s.put(key, garbage[i % len(garbage)])
                s.put(key, wrong if msg_type is not Twist else Odometry(
                    stamp_ns=5, x=0, y=0, yaw=0, v=0, w=0).to_bytes())
                s.put(key, _valid_like(msg_type, BAD_STAMPS[i % len(BAD_STAMPS)]))
                counts["puts"] += 3
            s.put(keys.goal, forged[0])
            s.put(keys.planner_status, forged[1])
            counts["puts"] += 2
            i += 1
            time.sleep(0.03)


def test_bus_fuzz_gives_the_figures_of_the_clean_run():
    """Items 2 and 3 end to end: nothing hostile on the bus changes a lockstep run."""
    args = ("--world", "open", "--planner", "apf", "--timeout", "60", *STEADY)
    code, clean, err = papf_run(*args)
    assert code == 0 and clean["outcome"] == "reached", err[-2000:]
    port = free_port()
    proc = start_papf_run(*args, port=port)
    stop, counts = threading.Event(), {"puts": 0}
    assert wait_port(port, 60), "the run's router never came up"
    fuzzer = threading.Thread(target=_fuzz, args=(f"tcp/127.0.0.1:{port}", stop, counts),
                              daemon=True)
    fuzzer.start()
    try:
        out, err = proc.communicate(timeout=240)
    finally:
        stop.set()
        fuzzer.join(10)
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    fuzzed = json.loads(out.strip().splitlines()[-1])
    assert counts["puts"] > 100
    assert {k: fuzzed[k] for k in FIGURES} == {k: clean[k] for k in FIGURES}, err[-3000:]
    assert "faults" not in fuzzed
    assert_no_orphans(port)


@pytest.mark.slow   # the slow tier (make test-quick leaves it out)
def test_a_dead_energy_meter_freezes_the_figures_and_is_named():
    """Item 4: the run ends at the meter's death, within the timeout, naming it."""
    port = free_port()
    proc = start_papf_run("--world", "energy", "--planner", "apf", "--timeout", "60", port=port)
    try:
        assert wait_port(port, 60)
        with zenoh.open(zenoh_config("client", [f"tcp/127.0.0.1:{port}"])) as s:
            started, moving = threading.Event(), threading.Event()

            def on_clock(smp) -> None:
                started.set()

            def on_battery(smp) -> None:
                # killed once its own figures pass 5 s of sim, not the clock: the meter drains
                # its streams in batches and, on 2 busy cores, was seen 3 s of sim behind
                if BatteryState.from_bytes(smp.payload.to_bytes()).stamp_ns > 5e9:
                    moving.set()
            subs = [s.declare_subscriber(Keys().clock, on_clock),
                    s.declare_subscriber(Keys().battery, on_battery)]
            assert started.wait(120), "the run never started"
            meter = pids_of("nodes.energy_meter", port)   # looked up before: killed at once
            assert meter, "no energy meter process"
            assert moving.wait(120), "the meter's figures never got to 5 s of sim time"
            for pid in meter:
                os.kill(pid, signal.SIGKILL)
            for sub in subs:
                sub.undeclare()
        out, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    res = json.loads(out.strip().splitlines()[-1])
    assert proc.returncode == 6 and res["outcome"] == "failed", err[-2000:]
    assert res["reason"].startswith("energy_meter exited") and "figures frozen at" in res["reason"]
    assert 3.0 <= res["sim_time_s"] < 20.0           # at the death, not ~10 s of wall later
    assert res["charge_mAh"] > 0 and res["path_length_m"] > 0
    assert_no_orphans(port)


def test_a_full_disk_ends_the_run_in_one_line_and_the_recording_is_recoverable(tiny_disk):
    """Item 5: no traceback, the run ends, the partial file is recoverable."""
    from papf.recording.recover import recover

    out = tiny_disk / "run.mcap"
    code, res, err = papf_run("--world", "energy", "--planner", "apf", "--timeout", "60",
                              "--record", str(out))
    assert code == 6 and res["outcome"] == "failed", err[-2000:]
    assert res["reason"].startswith("recorder exited with code 2: cannot write")
    assert "No space left on device" in res["reason"] and "papf recover" in res["reason"]
    assert "Traceback" not in err and res["sim_time_s"] < 60
    (tiny_disk / "fixed").mkdir()
    assert recover(out, tiny_disk.parent / "fixed.mcap").messages > 1000


def test_a_foreign_router_is_refused_before_anything_is_published():
    """Item 6: `papf run --port P` where another stack's router listens."""
    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    with Supervisor(show=lambda *_: False) as sup:
        sup.start("router", [sys.executable, "-m", "papf.launch.router", "--listen", endpoint])
        assert wait_port(port, 15.0)
        seen = []
        with zenoh.open(zenoh_config("client", [endpoint])) as s:
            sub = s.declare_subscriber("**", lambda smp: seen.append(str(smp.key_expr)))
            p = papf("run", "--world", "open", "--port", str(port), "--json", timeout=60)
            time.sleep(0.5)
            sub.undeclare()
    assert p.returncode == 2 and p.stdout == "" and "already listens" in p.stderr
    assert seen == [], seen


@pytest.fixture
def world(tmp_path) -> str:
    return str(write_world(tmp_path / "short.toml", SHORT))


def _clear_scan(stamp: int) -> bytes:
    """A "no obstacle anywhere" scan (what a spoofer wants the planner to see)."""
    return Scan(stamp_ns=stamp, angle_min=-3.14159, angle_increment=0.0175, range_min=0.2,
                range_max=12.0, ranges=np.full(360, np.inf, np.float32)).to_bytes()


class Attacker:
    """A keyless client of the run's router: attacks from its first moment on the bus until
    stopped — before the run starts, all through it and after — so that a run that starts
    fast on a loaded machine cannot begin before the attack does; ``started``: it saw the run."""

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
    args = ("--world", world, "--planner", "apf", "--timeout", "60", *FAST, *STEADY, "--record",
            str(record))
    proc = start_papf_run(*args, port=port)
    try:
        assert wait_port(port, 60), "the run's router never came up"
        with Attacker(f"tcp/127.0.0.1:{port}", flood) as attacker:
            out, err = proc.communicate(timeout=240)
        assert attacker.started.is_set(), "the attacker never saw the run"
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    return proc.returncode, json.loads(out.strip().splitlines()[-1]), err, attacker.sent


def test_nothing_a_keyless_peer_sends_changes_the_run(world, tmp_path):
    code, clean, err = papf_run("--world", world, "--planner", "apf", "--timeout", "60", *FAST,
                                *STEADY, "--record", str(tmp_path / "clean.mcap"))
    assert code == 0 and clean["outcome"] == "reached", err[-2000:]
    code, hit, err, sent = _attacked_run(world, tmp_path / "hit.mcap")
    assert sent.get("forged collision", 0) > 10 and sent.get("flood", 0) > 5, sent
    assert code == 0, (hit and hit.get("reason"), err[-3000:])   # the log tail: the flood's refusals
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


def _run_with_frozen(args: tuple[str, ...], module: str, at_ns: int = 0,
                     freeze_s: float | None = None) -> tuple[int, dict, str]:
    """``papf run args`` with ``module``'s processes stopped (SIGSTOP) once the sim clock
    reaches ``at_ns``, for ``freeze_s`` seconds (None: to the end); (exit code, JSON, stderr)."""
    port = free_port()
    proc = start_papf_run(*args, port=port)
    frozen: list[int] = []
    try:
        assert wait_port(port, 60)
        with zenoh.open(zenoh_config("client", [f"tcp/127.0.0.1:{port}"])) as s:
            there = threading.Event()
            sub = s.declare_subscriber(KEYS.key("sim/pose"), lambda sample: there.set() if
                                       Odometry.from_bytes(sample.payload.to_bytes()).stamp_ns
                                       >= at_ns else None)
            assert there.wait(120), "the run never started"
            sub.undeclare()
        frozen = pids_of(module, port)
        assert frozen
        for pid in frozen:
            os.kill(pid, signal.SIGSTOP)
        if freeze_s is not None:
            time.sleep(freeze_s)
            for pid in frozen:
                os.kill(pid, signal.SIGCONT)
        out, err = proc.communicate(timeout=240)
    finally:
        for pid in frozen:
            try:
                os.kill(pid, signal.SIGCONT)
            except ProcessLookupError:
                pass
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    return proc.returncode, json.loads(out.strip().splitlines()[-1]), err


def test_a_frozen_recorder_makes_the_run_say_its_recording_stopped(world, tmp_path):
    code, res, err = _run_with_frozen(("--world", world, "--planner", "apf", "--timeout", "60",
                                       *FAST, "--record", str(tmp_path / "frozen.mcap")),
                                      "nodes.recorder")
    assert code == 6 and res["outcome"] == "failed", err[-2000:]
    assert res["reason"].startswith("the recording stopped early") and "reached" in res["reason"]
    assert res["recording"]["complete"] is False


def test_a_frozen_planner_makes_the_run_name_where_its_lockstep_cycle_waits(tmp_path):
    """The planner stopped (SIGSTOP) for 2 s mid-run: the world simulator's lockstep wait
    (0.5 s) runs out, and the run's faults say where the cycle waits — every node's last stamps
    taken and put, the LiDAR's scan of the held instant among them, and the planner silent.
    Then the planner goes on, the lockstep comes back and the run reaches its goal."""
    # 5 m: a lockstep run of the short world could end before the planner is frozen; frozen
    # a few cycles in, when the planner has answered scans
    world = write_world(tmp_path / "long.toml", box_world("long", "5 m", 5.0, (0.6, 0.6)))
    _code, res, err = _run_with_frozen(("--world", str(world), "--planner", "apf", "--timeout",
                                        "60", *FAST, "--lockstep-timeout", "0.5"),
                                       "nodes.planner", at_ns=300_000_000, freeze_s=2.0)
    assert res["outcome"] == "reached", err[-2000:]
    held = [f for f in res["faults"] if f.startswith("launcher: the nodes' last stamps: ")]
    assert held, res["faults"]
    print(held[0])
    nodes = dict(part.split(" ", 1) for part in held[0].split("stamps: ", 1)[1].split(" | "))
    assert nodes["no"] == "answer from planner"
    assert "took sim/pose" in nodes["lidar_sim"] and "put scan" in nodes["lidar_sim"]
    assert "took cmd_vel" in nodes["base_driver"] and "peer links)" in nodes["base_driver"]
    assert "lockstep held: " in err
