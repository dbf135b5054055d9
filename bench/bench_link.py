"""The link emulator's own cost: ``papf bench link`` (``python bench/bench_link.py``).

``papf link`` (a real process, as ``papf run --link`` starts it) forwards to an echo server
in this process; the same pings also go to the echo server directly.

- **added latency**: ``--pings`` round trips of a 64-byte message, through the link and
  directly; the link's added one-way latency is half the difference of the round trips
  (p50, p99, max) — at ``--spec delay=0`` (the default) it is the emulator's own overhead
  (asyncio's millisecond timers, two extra socket hops), with a delay it shows how exactly
  that delay is applied;
- **throughput**: ``--megabytes`` sent one way through the link as fast as it takes them
  (MB/s), and directly for comparison.

Prints one JSON object with the machine's 1-minute load average (other processes on the
cores inflate the figures); ``--csv FILE`` appends it as a row. Speed is reported, never
asserted.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import signal
import socket
import socketserver
import subprocess
import sys
import threading
import time
from pathlib import Path

from bench.csvrows import write_rows
from common.ports import plain
from papf.launch.supervisor import free_port, wait_port

FIELDS = ["spec", "pings", "direct_rtt_p50_ms", "link_rtt_p50_ms", "added_one_way_p50_ms",
          "added_one_way_p99_ms", "added_one_way_max_ms", "megabytes", "direct_MBps", "link_MBps",
          "load_avg", "machine"]


class _Echo(socketserver.BaseRequestHandler):
    def handle(self) -> None:
        self.request.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        while data := self.request.recv(1 << 16):
            if self.server.echo:
                self.request.sendall(data)


def _server(echo: bool) -> socketserver.ThreadingTCPServer:
    socketserver.ThreadingTCPServer.allow_reuse_address = True
    srv = socketserver.ThreadingTCPServer(("127.0.0.1", 0), _Echo)
    srv.daemon_threads = True
    srv.echo = echo
    threading.Thread(target=srv.serve_forever, daemon=True).start()
    return srv


def _pings(port: int, n: int) -> list[float]:
    """Round trips [s] of a 64-byte message, one at a time."""
    out = []
    with socket.create_connection(("127.0.0.1", port)) as s:
        s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        msg = b"x" * 64
        for _ in range(n):
            t = time.perf_counter()
            s.sendall(msg)
            got = 0
            while got < len(msg):
                got += len(s.recv(1 << 16))
            out.append(time.perf_counter() - t)
            time.sleep(0.005)
    return out


def _throughput(port: int, megabytes: float) -> float:
    """MB/s of ``megabytes`` sent one way, until the sink has them all (closing waits)."""
    block = b"\0" * (1 << 16)
    total = int(megabytes * 1e6)
    t = time.perf_counter()
    with socket.create_connection(("127.0.0.1", port)) as s:
        sent = 0
        while sent < total:
            s.sendall(block)
            sent += len(block)
        s.shutdown(socket.SHUT_WR)
        s.recv(1)          # the sink closes when it has read everything
    return megabytes / (time.perf_counter() - t)


def _pct(xs: list[float], p: float) -> float:
    xs = sorted(xs)
    return xs[min(len(xs) - 1, int(round(p / 100 * (len(xs) - 1))))]


def main(spec: str, pings: int, megabytes: float) -> dict:
    echo, sink = _server(True), _server(False)
    ports = {"link": free_port(), "sink_link": free_port()}
    procs = [subprocess.Popen([sys.executable, "-m", "papf", "link", "--listen",
                               f"tcp/127.0.0.1:{ports[k]}", "--to", f"tcp/127.0.0.1:{srv.server_address[1]}",
                               "--spec", spec], stderr=subprocess.DEVNULL, start_new_session=True)
             for k, srv in (("link", echo), ("sink_link", sink))]
    try:
        for k in ports:
            if not wait_port(ports[k], 30.0):
                raise SystemExit("papf link did not come up")
        _pings(ports["link"], 5)                       # warm up both paths
        direct = _pings(echo.server_address[1], pings)
        linked = _pings(ports["link"], pings)
        d50 = _pct(direct, 50)
        added = sorted((x - d50) / 2 for x in linked)
        return {"spec": spec, "pings": pings, "direct_rtt_p50_ms": round(d50 * 1e3, 3),
                "link_rtt_p50_ms": round(_pct(linked, 50) * 1e3, 3),
                "added_one_way_p50_ms": round(_pct(added, 50) * 1e3, 3),
                "added_one_way_p99_ms": round(_pct(added, 99) * 1e3, 3),
                "added_one_way_max_ms": round(added[-1] * 1e3, 3), "megabytes": megabytes,
                "direct_MBps": round(_throughput(sink.server_address[1], megabytes), 1),
                "link_MBps": round(_throughput(ports["sink_link"], megabytes), 1),
                "load_avg": round(os.getloadavg()[0], 2),
                "machine": f"{platform.machine()} {os.cpu_count()} cpus"}
    finally:
        for p in procs:
            os.killpg(p.pid, signal.SIGTERM)
            p.wait(timeout=15)
        echo.shutdown()
        sink.shutdown()


if __name__ == "__main__":
    p = argparse.ArgumentParser(prog="papf bench link", description=plain(__doc__.splitlines()[0]))
    p.add_argument("--spec", default="delay=0", help="the link (papf run --link SPEC; delay=0)")
    p.add_argument("--pings", type=int, default=500, help="round trips measured (500)")
    p.add_argument("--megabytes", type=float, default=200.0, help="sent for the throughput (200)")
    p.add_argument("--csv", metavar="FILE", help="append the result as a CSV row")
    a = p.parse_args()
    if not 10 <= a.pings <= 100_000 or not 1.0 <= a.megabytes <= 10_000.0:
        raise SystemExit("--pings in [10, 100000], --megabytes in [1, 10000]")
    row = main(a.spec, a.pings, a.megabytes)
    print(json.dumps(row, indent=2))
    if a.csv:
        write_rows(Path(a.csv), FIELDS, [row], append=True)
