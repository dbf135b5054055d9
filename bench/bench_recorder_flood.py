"""Recorder under a byte flood (issue 31): its memory, and whether every real odometry sample is kept.

    papf bench recorder-flood [--flood-s 8] [--payload-kb 512] [--keyed both|yes|no] [--csv F]

Starts an embedded router on a free port and a ``python -m nodes.recorder`` process, then for
``--flood-s`` seconds this process publishes real odometry at 50 Hz (wall) on ``rosbot/odom``
while a second session floods ``rosbot/scan`` (a recorded key) with ``--payload-kb`` payloads as
fast as it can. The recorder's resident memory is sampled every 50 ms (``/proc/PID/status``
VmRSS). Then SIGTERM, and the file is read back: odometry samples recorded of those sent, flood
samples recorded, and the drops the recording's summary names (``not_recorded``).

``--keyed yes``: the recorder holds a run's key and run id, the odometry is sealed (a run's
recorder; the flood has no seal and is refused before it costs anything); ``no``: a keyless
recorder (``papf record`` by hand), where the per-key budgets alone bound it; ``both`` (default)
runs the two. One JSON object on stdout; with ``--csv``, one row per case appended.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import zenoh

from common import runauth, seal
from common.transport import wait_alive, zenoh_config
from papf.launch.supervisor import free_port
from papf.recording import open_recording
from schemas import Keys, Odometry

FIELDS = ("keyed", "flood_s", "payload_kb", "peak_rss_mb", "odom_sent", "odom_recorded",
          "flood_sent", "flood_recorded", "flood_dropped_named", "note")
KEYS = Keys()


def _rss_mb(pid: int) -> float:
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    except OSError:
        pass
    return 0.0


def _flood(endpoint: str, payload: bytes, stop: threading.Event, sent: list[int]) -> None:
    with zenoh.open(zenoh_config("client", [endpoint])) as s:
        pub = s.declare_publisher(KEYS.scan)
        while not stop.is_set():
            pub.put(payload)
            sent[0] += 1


def case(keyed: bool, flood_s: float, payload_kb: int, tmp: Path) -> dict:
    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    key, run = runauth.new_key(), seal.new_run_id()
    env = {k: v for k, v in os.environ.items() if k not in (runauth.ENV, seal.RUN_ID_ENV)}
    if keyed:
        env.update({runauth.ENV: key, seal.RUN_ID_ENV: run})
    out = tmp / f"flood-{'keyed' if keyed else 'keyless'}.mcap"
    with zenoh.open(zenoh_config("router", listen=[endpoint], scout_delay_ms=0)) as session:
        rec = subprocess.Popen([sys.executable, "-m", "nodes.recorder", "--out", str(out),
                                "--connect", endpoint], env=env, stdout=subprocess.DEVNULL,
                               stderr=subprocess.DEVNULL, start_new_session=True)
        try:
            assert not wait_alive(session, KEYS, ["recorder"], 60.0), "the recorder never came up"
            sealer = seal.Sealer(bytes.fromhex(key), bytes.fromhex(run)) if keyed else None
            stop, flood_sent, peak = threading.Event(), [0], 0.0
            flooder = threading.Thread(target=_flood, daemon=True,
                                       args=(endpoint, os.urandom(payload_kb * 1024), stop,
                                             flood_sent))
            # as every node puts (common.transport.Node): a full link waits, never drops
            pub = session.declare_publisher(KEYS.odom,
                                            congestion_control=zenoh.CongestionControl.BLOCK)
            flooder.start()
            t0, n, next_rss = time.monotonic(), 0, 0.0
            while (now := time.monotonic()) - t0 < flood_s:
                if now >= t0 + n * 0.02:
                    payload = Odometry(stamp_ns=n * 20_000_000, x=0.01 * n, y=0.0, yaw=0.0,
                                       v=0.5, w=0.0).to_bytes()
                    if sealer is None:
                        pub.put(payload)
                    else:
                        pub.put(payload, attachment=sealer.seal(KEYS.odom, payload))
                    n += 1
                if now >= next_rss:
                    peak, next_rss = max(peak, _rss_mb(rec.pid)), now + 0.05
                time.sleep(0.002)
            stop.set()
            flooder.join(10)
            time.sleep(1.0)   # the queue drains
            peak = max(peak, _rss_mb(rec.pid))
            rec.send_signal(signal.SIGTERM)
            rec.wait(timeout=60)
        finally:
            if rec.poll() is None:
                os.killpg(rec.pid, signal.SIGKILL)
                rec.wait()
    with open_recording(out) as r:
        counts = r.counts()
        dropped = {k: json.loads(v) for k, v in r.metadata.get("not_recorded", {}).items()}
    named = sum(dropped.get(KEYS.scan, {}).values())
    return {"keyed": "yes" if keyed else "no", "flood_s": flood_s, "payload_kb": payload_kb,
            "peak_rss_mb": round(peak, 1), "odom_sent": n,
            "odom_recorded": counts.get(KEYS.odom, 0), "flood_sent": flood_sent[0],
            "flood_recorded": counts.get(KEYS.scan, 0), "flood_dropped_named": named,
            "note": "measured under load (2 cores shared by seven engineers)"}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="papf bench recorder-flood", description=__doc__.split("\n")[0])
    ap.add_argument("--flood-s", type=float, default=8.0)
    ap.add_argument("--payload-kb", type=int, default=512)
    ap.add_argument("--keyed", choices=("both", "yes", "no"), default="both")
    ap.add_argument("--csv", help="append one row per case to this CSV")
    args = ap.parse_args(argv)
    rows = []
    with tempfile.TemporaryDirectory(prefix="papf-flood-") as tmp:
        for keyed in {"both": (True, False), "yes": (True,), "no": (False,)}[args.keyed]:
            rows.append(case(keyed, args.flood_s, args.payload_kb, Path(tmp)))
            print(f"recorder-flood keyed={rows[-1]['keyed']}: peak {rows[-1]['peak_rss_mb']} MB, "
                  f"odometry {rows[-1]['odom_recorded']}/{rows[-1]['odom_sent']}", file=sys.stderr)
    if args.csv:
        from bench.csvrows import write_rows
        write_rows(Path(args.csv), FIELDS, rows, append=True)
    print(json.dumps({"cases": rows}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
