"""Command-to-wheel latency over the robot/laptop split; prints one JSON object.

    .venv/bin/python bench/bench_latency.py [--probes 40] [--split auto|netns|loopback]

Robot side: ``papf launch hil-robot`` (router + rosbot driver) and the ROSbot emulator,
which logs the monotonic time each CDR ``cmd_vel`` reaches it (``--trace``): the wheel
command. Laptop side: a probe that steps our ``<ns>/cmd_vel`` between 0 and 0.2 m/s
(holding each for 0.3 s, at the planner's 10 Hz) and logs when it put each step.
Latency of a step = first wheel command that moves towards the new target - the put.
Both sides read the same CLOCK_MONOTONIC (network namespaces share the kernel clock).

``netns`` (root): two network namespaces joined by a veth pair with private addresses
this script creates (10.231.0.1/30, .2) and deletes; ``loopback``: both sides on 127.0.0.1.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from common.cliparse import ArgumentParser
from common.ports import plain

PY = sys.executable
ROOT = Path(__file__).resolve().parent.parent
NS = "benchlat"
STEP_V = 0.2          # [m/s] probe step (the gate ramps towards it; its first move counts)
HOLD_S = 0.3          # [s] each level is held this long
PERIOD_S = 0.1        # [s] command period (the planner's 10 Hz)


def _ip(*args: str) -> None:
    subprocess.run(["ip", *args], check=True, capture_output=True, timeout=20)


def netns_setup(tag: str) -> tuple[list[str], list[str], str, callable]:
    r, lap, dr, dl = f"papf_br{tag}", f"papf_bl{tag}", f"br{tag}"[:15], f"bl{tag}"[:15]

    def teardown():
        for ns in (r, lap):
            subprocess.run(["ip", "netns", "del", ns], capture_output=True, timeout=20)
    try:
        _ip("netns", "add", r)
        _ip("netns", "add", lap)
        _ip("link", "add", dr, "type", "veth", "peer", "name", dl)
        _ip("link", "set", dr, "netns", r)
        _ip("link", "set", dl, "netns", lap)
        _ip("-n", r, "addr", "add", "10.231.0.1/30", "dev", dr)
        _ip("-n", lap, "addr", "add", "10.231.0.2/30", "dev", dl)
        for ns, dev in ((r, dr), (lap, dl)):
            _ip("-n", ns, "link", "set", "lo", "up")
            _ip("-n", ns, "link", "set", dev, "up")
    except (subprocess.CalledProcessError, OSError):
        teardown()
        raise
    return ["ip", "netns", "exec", r], ["ip", "netns", "exec", lap], "10.231.0.1", teardown


def probe(endpoint: str, probes: int, out: str) -> int:
    """Laptop side: step commands, log each step's put time (monotonic ns)."""
    import zenoh

    from common.transport import wait_alive, zenoh_config
    from schemas import Keys, Twist

    keys = Keys(NS)
    with zenoh.open(zenoh_config("client", [endpoint])) as s, open(out, "w") as log:
        if wait_alive(s, keys, ["base_driver", "rosbot_emulator"], 60.0):
            return 1
        pub = s.declare_publisher(keys.cmd_vel)
        for i in range(2 * probes + 1):
            target = STEP_V if i % 2 else 0.0
            t_end = time.monotonic() + HOLD_S
            first = True
            while time.monotonic() < t_end:
                t = time.monotonic_ns()
                pub.put(Twist(stamp_ns=0, v=target, w=0.0).to_bytes())
                if first and i:
                    log.write(json.dumps({"t_ns": t, "v": target}) + "\n")
                    first = False
                time.sleep(PERIOD_S)
        pub.undeclare()
    return 0


def latencies(steps: list[dict], wheel: list[dict]) -> list[float]:
    """[ms] per step: first wheel command after the put that moves towards the new target."""
    out, j = [], 0
    for step in steps:
        while j < len(wheel) and wheel[j]["t_ns"] < step["t_ns"]:
            j += 1
        prev = wheel[j - 1]["v"] if j else 0.0
        k = j
        while k < len(wheel) and not (wheel[k]["v"] > prev if step["v"] > prev
                                      else wheel[k]["v"] < prev):
            k += 1
        if k < len(wheel):
            out.append((wheel[k]["t_ns"] - step["t_ns"]) / 1e6)
    return out


def main() -> int:
    ap = ArgumentParser(prog="papf bench latency", description=plain(__doc__.splitlines()[0]))
    ap.add_argument("--probes", type=int, default=40, help="steps up (and as many down)")
    ap.add_argument("--split", choices=("auto", "netns", "loopback"), default="auto")
    ap.add_argument("--probe", metavar="OUT", help=argparse.SUPPRESS)
    ap.add_argument("--connect", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.probe:
        return probe(a.connect, a.probes, a.probe)
    split = a.split
    if split == "auto":
        split = "netns" if os.geteuid() == 0 and shutil.which("ip") else "loopback"
    teardown = lambda: None  # noqa: E731
    robot_pre, laptop_pre, host = [], [], "127.0.0.1"
    if split == "netns":
        robot_pre, laptop_pre, host, teardown = netns_setup(str(os.getpid())[-6:])
    port = 7447 if split == "netns" else _free_port()
    endpoint = f"tcp/{host}:{port}"
    tmp = Path(tempfile.mkdtemp(prefix="papf-lat-"))
    trace, steps = tmp / "wheel.jsonl", tmp / "steps.jsonl"
    procs = []
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    try:
        procs.append(subprocess.Popen(
            [*robot_pre, PY, "-m", "papf", "launch", "hil-robot", "--listen", endpoint,
             "--namespace", NS], start_new_session=True, env=env, stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL))
        subprocess.run([*robot_pre, PY, "-c", f"from papf.launch.supervisor import wait_port; "
                        f"assert wait_port({port}, 30, '{host}')"], check=True, env=env, timeout=60)
        procs.append(subprocess.Popen(
            [*robot_pre, PY, "-m", "papf", "rosbot-emulator", "--connect", endpoint, "--namespace", NS,
             "--cmd-timeout", "0", "--trace", str(trace)], start_new_session=True, env=env,
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        cmd = [*laptop_pre, PY, str(Path(__file__).resolve()), "--probe", str(steps),
               "--connect", endpoint, "--probes", str(a.probes)]
        subprocess.run(cmd, check=True, env=env, timeout=60 + a.probes * 2 * HOLD_S * 3)
    finally:
        for p in reversed(procs):
            if p.poll() is None:
                os.killpg(p.pid, signal.SIGTERM)
        for p in procs:
            try:
                p.wait(timeout=15)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
        teardown()
    read = lambda f: [json.loads(x) for x in f.read_text().splitlines() if x.endswith("}")]  # noqa: E731
    lat = sorted(latencies(read(steps), read(trace)))
    q = statistics.quantiles(lat, n=100, method="inclusive") if len(lat) > 1 else lat * 99
    print(json.dumps({"bench": "command_to_wheel_latency", "split": split, "steps": len(lat),
                      "p50_ms": round(statistics.median(lat), 3), "p99_ms": round(q[98], 3),
                      "max_ms": round(lat[-1], 3), "mean_ms": round(statistics.fmean(lat), 3),
                      "path": "laptop put <ns>/cmd_vel -> router -> base_driver (rosbot) -> "
                              "CDR cmd_vel -> emulator"}))
    return 0


def _free_port() -> int:
    sys.path.insert(0, str(ROOT))
    from papf.launch.supervisor import free_port

    return free_port()


if __name__ == "__main__":
    sys.exit(main())
