"""Recorder throughput: small messages/s recorded without loss over a real router.

    .venv/bin/python bench/bench_recorder.py [--rates 20000 50000 80000] [--duration 3]

Starts the embedded router on a free port, then for each target rate a fresh
``python -m nodes.recorder`` process; this process publishes ``rate x duration``
Twist messages (about 50 bytes, ``stamp_ns`` = sequence number) paced in 1 ms
bursts with the stack's default QoS (congestion control DROP, like every node), waits
for the stream to settle, stops the recorder with SIGTERM and counts what the file
holds. Prints one JSON object: per rate the achieved publish rate, messages
recorded and lost, the recorder's CPU seconds; and the highest lossless rate.

``--baseline`` also runs each rate against a no-op subscriber process (same FIFO
queue, counts payloads, writes nothing): losses it shows too come from the pipeline
(publisher, router, CPU sharing), not from the recorder.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import zenoh

from common.cliparse import ArgumentParser
from common.ports import plain
from common.transport import wait_alive, zenoh_config
from papf.launch.supervisor import free_port, wait_port
from papf.recording import open_recording
from schemas import Keys, Twist

ROOT = Path(__file__).resolve().parents[1]
SETTLE_S = 1.0  # [s] after the last put before stopping the recorder

# The no-op subscriber of --baseline: argv = endpoint, namespace, file to write the count to.
BASELINE = """
import signal, sys, threading, zenoh
from common.transport import zenoh_config
stop = threading.Event()
signal.signal(signal.SIGTERM, lambda *_: stop.set())
endpoint, ns, out = sys.argv[1:4]
with zenoh.open(zenoh_config("client", [endpoint])) as s:
    sub = s.declare_subscriber(ns + "/**", zenoh.handlers.FifoChannel(1_000_000))
    token = s.liveliness().declare_token(ns + "/alive/recorder")
    n = 0
    while True:
        sample = sub.try_recv()
        if sample is None:
            if stop.is_set():
                break
            stop.wait(0.01)
            continue
        sample.payload.to_bytes()
        n += 1
    open(out, "w").write(str(n))
"""


def spawn(*args: str) -> subprocess.Popen:
    """``python -m <args>`` (or ``python -c`` code) in its own process group, quiet."""
    return subprocess.Popen([sys.executable, *(args if args[0] == "-c" else ("-m", *args))],
                            cwd=ROOT, start_new_session=True,
                            stdout=subprocess.DEVNULL)  # stderr: shown, for failures


def stop(proc: subprocess.Popen, sig: int = signal.SIGTERM, timeout: float = 10.0) -> None:
    if proc.poll() is None:
        os.killpg(proc.pid, sig)
        try:
            proc.wait(timeout)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()


def cpu_seconds(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def publish_paced(pub, payloads: list[bytes], rate: float) -> float:
    """Put every payload, ``rate`` per second in 1 ms bursts; returns the achieved rate."""
    start = time.perf_counter()
    sent = 0
    while sent < len(payloads):
        due = min(len(payloads), int((time.perf_counter() - start) * rate) + 1)
        while sent < due:
            pub.put(payloads[sent])
            sent += 1
        time.sleep(0.001)
    return sent / (time.perf_counter() - start)


def run_rate(session, endpoint: str, ns: str, rate: float, duration: float, out: Path,
             baseline: bool = False) -> dict:
    """Publish at ``rate`` to a fresh recorder (or no-op subscriber); count what arrived."""
    keys = Keys(ns)
    n = int(rate * duration)
    payloads = [Twist(stamp_ns=i, v=0.5, w=0.1).to_bytes() for i in range(n)]
    if baseline:
        sub = spawn("-c", BASELINE, endpoint, ns, str(out))
    else:
        sub = spawn("nodes.recorder", "--out", str(out), "--connect", endpoint, "--namespace", ns,
                    "--log-level", "WARNING")
    try:
        if wait_alive(session, keys, ["recorder"], timeout_s=20):
            raise RuntimeError("subscriber process did not come up")
        pub = session.declare_publisher(keys.cmd_vel)
        deadline = time.monotonic() + 10
        while not pub.matching_status.matching and time.monotonic() < deadline:
            time.sleep(0.01)  # the router has not told us about the subscriber yet
        cpu0 = cpu_seconds(sub.pid)
        achieved = publish_paced(pub, payloads, rate)
        time.sleep(SETTLE_S)
        cpu = cpu_seconds(sub.pid) - cpu0
        pub.undeclare()
    finally:
        stop(sub)
    if baseline:
        received = int(out.read_text()) if out.exists() else 0  # 0: the subscriber died
    else:
        with open_recording(out) as r:
            received = len({m.log_time_ns for m in r.raw(keys.cmd_vel, log_time_order=False)})
    out.unlink(missing_ok=True)
    return {"subscriber": "no-op" if baseline else "recorder", "target_per_s": rate,
            "published_per_s": round(achieved), "sent": n, "received": received,
            "lost": n - received, "subscriber_cpu_s": round(cpu, 2),
            "payload_bytes": len(payloads[0])}


def main(rates: list[float], duration: float, baseline: bool = False) -> dict:
    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    router = spawn("papf.launch.router", "--listen", endpoint)
    results = []
    try:
        if not wait_port(port, 20.0):
            raise RuntimeError(f"router did not start on port {port}")
        with zenoh.open(zenoh_config("client", [endpoint])) as session, \
                tempfile.TemporaryDirectory() as tmp:
            for i, rate in enumerate(rates):
                for j, kind in enumerate([False, True] if baseline else [False]):
                    results.append(run_rate(session, endpoint, f"bench{i}x{j}", rate, duration,
                                            Path(tmp) / f"r{i}x{j}.out", kind))
    finally:
        stop(router)
    lossless = [r["published_per_s"] for r in results
                if r["lost"] == 0 and r["subscriber"] == "recorder"]
    return {"bench": "recorder", "duration_s": duration, "cpus": os.cpu_count(),
            "runs": results, "max_lossless_per_s": max(lossless, default=0)}


if __name__ == "__main__":
    p = ArgumentParser(prog="papf bench recorder", description=plain(__doc__.splitlines()[0]))
    p.add_argument("--rates", type=float, nargs="+", default=[20_000, 50_000, 80_000, 120_000],
                   help="target publish rates [msgs/s]")
    p.add_argument("--duration", type=float, default=3.0, help="publishing time per rate [s]")
    p.add_argument("--baseline", action="store_true",
                   help="also measure a no-op subscriber at each rate (pipeline losses)")
    a = p.parse_args()
    print(json.dumps(main(a.rates, a.duration, a.baseline), indent=2))
