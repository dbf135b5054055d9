"""What receiving one sample costs a Python node: a callback on Zenoh's thread against a
channel its main thread drains, with that main thread idle or busy (docs/performance.md
"Receiving a sample").

A publisher process puts ``--topics`` samples of ``--bytes`` bytes (with a 39-byte
attachment, a seal's size), one per topic, every ``--period-ms``: the burst a fleet's
planner takes per cycle (a scan, odometry and obstacle tracks per robot). The subscriber
process takes them either

- ``callback``: a Python callable run on Zenoh's receiving thread (``Callback(indirect=False)``,
  what ``common.transport.Node.subscribe`` declares): it copies payload and attachment and
  queues them for the main thread, as a node's handler does; or
- ``channel``: Zenoh's FIFO channel per topic, drained by the main thread (``try_recv``),
  what the energy meter and the launcher do;

while its main thread waits for the queue (``idle``) or runs pure-Python work between drains
(``busy``: a planner or a LiDAR casting while the next samples arrive). Each row: the
samples taken and the CPU of the subscriber's threads other than the main one per sample
(Zenoh's own and the callbacks: what the process pays besides its work), from
``/proc/<pid>/task``.

    papf bench rx [--seconds 6] [--label L --csv docs/data/rx-cost.csv]
"""

from __future__ import annotations

import argparse
import json
import os
import queue
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bench.csvrows import check_csv, emit, replace_label  # noqa: E402

FIELDS = ("label", "handler", "main_thread", "samples", "rx_us_per_sample", "main_cpu_s",
          "load_avg_1min")
HANDLERS, LOADS = ("callback", "channel"), ("idle", "busy")
TICK_S = 0.01   # [s] the main thread's wait for the queue (idle) or between drains (busy)


def _session(listen: str | None = None, connect: str | None = None):
    """A peer session on loopback, as the stack's nodes open theirs (no multicast scouting)."""
    import zenoh

    from common.transport import zenoh_config

    return zenoh.open(zenoh_config("peer", connect=[connect] if connect else (),
                                   listen=[listen] if listen else ()))


def publish(endpoint: str, topics: int, size: int, period_s: float, seconds: float) -> None:
    """The publisher process: a burst of one sample per topic every ``period_s``."""
    session = _session(listen=endpoint)
    pubs = [session.declare_publisher(f"bench/rx/{i}") for i in range(topics)]
    payload, attachment = os.urandom(size), os.urandom(39)
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        for pub in pubs:
            pub.put(payload, attachment=attachment)
        time.sleep(period_s)
    session.close()


def _thread_cpu_s() -> tuple[float, float]:
    """(main thread, all other threads) CPU seconds of this process."""
    tick = os.sysconf("SC_CLK_TCK")
    main = other = 0.0
    for tid in os.listdir("/proc/self/task"):
        with open(f"/proc/self/task/{tid}/stat") as fh:
            fields = fh.read().rsplit(")", 1)[1].split()
        cpu = (int(fields[11]) + int(fields[12])) / tick
        if int(tid) == os.getpid():
            main += cpu
        else:
            other += cpu
    return main, other


def subscribe(endpoint: str, topics: int, handler: str, load: str, seconds: float) -> dict:
    """The subscriber: take samples for ``seconds`` as ``handler`` with the main thread
    ``load``; the row of figures."""
    import zenoh

    session = _session(connect=endpoint)
    inbox: queue.SimpleQueue = queue.SimpleQueue()
    taken = [0]

    def take(sample) -> None:   # what a node's handler does with a sample, short of decoding
        attachment = sample.attachment
        inbox.put((sample.payload.to_bytes(), None if attachment is None else attachment.to_bytes()))
        taken[0] += 1

    keys = [f"bench/rx/{i}" for i in range(topics)]
    if handler == "callback":
        subs = [session.declare_subscriber(k, zenoh.handlers.Callback(take, indirect=False))
                for k in keys]
    else:
        subs = [session.declare_subscriber(k, zenoh.handlers.FifoChannel(4096)) for k in keys]
    main0, other0 = _thread_cpu_s()
    end, x = time.monotonic() + seconds, 0
    while time.monotonic() < end:
        if load == "busy":
            for _ in range(20_000):   # ~1 ms of pure-Python work holding the GIL
                x += 1
        if handler == "channel":
            for sub in subs:
                while (sample := sub.try_recv()) is not None:
                    take(sample)
        try:
            while True:
                inbox.get(timeout=0 if load == "busy" else TICK_S)
        except queue.Empty:
            pass
    main1, other1 = _thread_cpu_s()
    session.close()
    n = max(taken[0], 1)
    return {"handler": handler, "main_thread": load, "samples": taken[0],
            "rx_us_per_sample": round((other1 - other0) / n * 1e6, 1),
            "main_cpu_s": round(main1 - main0, 2), "load_avg_1min": round(os.getloadavg()[0], 1)}


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(prog="papf bench rx", description=__doc__.split("\n\n")[0])
    parser.add_argument("--topics", type=int, default=24, help="samples per burst (default 24)")
    parser.add_argument("--bytes", type=int, default=3000, help="payload size (default 3000)")
    parser.add_argument("--period-ms", type=float, default=25.0, help="between bursts (default 25)")
    parser.add_argument("--seconds", type=float, default=6.0, help="per row (default 6)")
    parser.add_argument("--port", type=int, default=0, help="the publisher's port (default: free)")
    parser.add_argument("--label", default="", help="the rows' label (with --csv: replaces that label's)")
    parser.add_argument("--csv", type=Path, help="write the rows to this CSV")
    parser.add_argument("--role", choices=("pub", "sub"), help=argparse.SUPPRESS)
    parser.add_argument("--handler", choices=HANDLERS, help=argparse.SUPPRESS)
    parser.add_argument("--load", choices=LOADS, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    for name in ("topics", "bytes", "period_ms", "seconds"):
        value = getattr(args, name)
        if not value > 0 or value != value:
            parser.error(f"--{name.replace('_', '-')} {value!r}: must be a number > 0")
    endpoint = f"tcp/127.0.0.1:{args.port}"
    if args.role == "pub":
        publish(endpoint, args.topics, args.bytes, args.period_ms / 1e3, args.seconds)
        return
    if args.role == "sub":
        print(json.dumps(subscribe(endpoint, args.topics, args.handler, args.load, args.seconds)))
        return
    if args.csv:
        check_csv(args.csv, FIELDS)   # a table of this benchmark or a new file, before the work
    from papf.launch.supervisor import free_port

    kept: list[dict] = []
    for handler in HANDLERS:
        for load in LOADS:
            port = str(free_port())
            common = ["--topics", str(args.topics), "--bytes", str(args.bytes),
                      "--period-ms", str(args.period_ms), "--port", port]
            pub = subprocess.Popen([sys.executable, __file__, "--role", "pub", *common,
                                    "--seconds", str(args.seconds + 3)])
            time.sleep(1.0)   # the publisher listens
            out = subprocess.run([sys.executable, __file__, "--role", "sub", *common,
                                  "--seconds", str(args.seconds), "--handler", handler,
                                  "--load", load], capture_output=True, text=True, check=True)
            pub.wait()
            emit(kept, json.loads(out.stdout.strip().splitlines()[-1]), args.label)
    if args.csv:
        replace_label(args.csv, FIELDS, args.label,
                      [{k: v for k, v in r.items() if k != "label"} for r in kept])


if __name__ == "__main__":
    main()
