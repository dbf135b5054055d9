"""Recorder node: every sample under a key expression into a crash-safe MCAP (DESIGN.md §8).

    python -m nodes.recorder --out run.mcap [--keys 'rosbot/**'] [--meta world=energy ...]

Ports: :mod:`nodes.recorder.ports` (``--help`` prints them); liveliness ``<ns>/alive/recorder``.

Samples are queued by Zenoh itself (a FIFO channel handler: no Python runs on the
receive thread) and drained in batches by the main thread into
:class:`papf.recording.RunWriter`, which flushes at least every ``--flush-interval``
seconds. SIGINT/SIGTERM: drain the queue, write the summary and footer, exit 0.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import zenoh

from common.errors import ConfigError, PapfError
from common.ports import describe
from common.transport import Node, add_zenoh_args, open_node, setup_logging
from nodes.recorder.ports import PORTS, VARIANTS
from nodes.recorder.writer import COMPRESSIONS, FLUSH_INTERVAL_S, RunWriter, WriterStats

NAME = "recorder"
QUEUE_CAPACITY = 1_000_000  # [samples] Zenoh-side buffer: 20 s at 50 kHz before back-pressure
BATCH = 5_000               # [samples] drained between stop/flush checks
IDLE_WAIT_S = 0.01           # [s] sleep when the queue is empty (the FIFO holds the backlog)
FINAL_DRAIN_S = 2.0         # [s] at most spent draining the queue after a stop request
STATUS_EVERY_S = 10.0       # [s] wall time between progress log lines


def drain(subscriber, writer: RunWriter, max_samples: int) -> int:
    """Write up to ``max_samples`` queued samples; returns how many were taken.

    The hot loop of the recorder: locals only, one ``try_recv`` per sample.
    """
    recv, write, now, put = subscriber.try_recv, writer.write, time.time_ns, zenoh.SampleKind.PUT
    n = 0
    while n < max_samples:
        sample = recv()
        if sample is None:
            break
        n += 1
        if sample.kind == put:  # a DELETE has no payload to record
            write(str(sample.key_expr), sample.payload.to_bytes(), now())
    return n


def record(node: Node, out: str | Path, keys_expr: str, metadata: dict[str, str],
           compression: str = "zstd", flush_interval_s: float = FLUSH_INTERVAL_S,
           queue_capacity: int = QUEUE_CAPACITY) -> WriterStats:
    """Record until ``node.stop``; returns the writer's counts. The file is complete on return."""
    meta = {"namespace": node.keys.ns, "keys": keys_expr, **metadata}
    with RunWriter(out, meta, compression=compression, flush_interval_s=flush_interval_s) as writer:
        sub = node.session.declare_subscriber(keys_expr, zenoh.handlers.FifoChannel(queue_capacity))
        try:
            node.ready()
            node.log.info("recording %s into %s", keys_expr, out)
            _loop(node, sub, writer)
            deadline = time.monotonic() + FINAL_DRAIN_S
            while drain(sub, writer, BATCH) and time.monotonic() < deadline:
                pass
        finally:
            sub.undeclare()
    node.log.info("closed %s: %d messages, %d bytes, %d channels", out, writer.stats.messages,
                  writer.stats.bytes, writer.stats.channels)
    return writer.stats


def _loop(node: Node, sub, writer: RunWriter) -> None:
    next_status = time.monotonic() + STATUS_EVERY_S
    last_count = 0
    while not node.stop:
        if drain(sub, writer, BATCH) == 0:
            writer.maybe_flush()
            node.stop.event.wait(IDLE_WAIT_S)
        if time.monotonic() >= next_status:
            count = writer.stats.messages
            node.log.info("%d messages (%.0f/s)", count, (count - last_count) / STATUS_EVERY_S)
            next_status, last_count = next_status + STATUS_EVERY_S, count


def parse_meta(items: list[str]) -> dict[str, str]:
    """``["world=energy", "seed=1"]`` -> dict; a value may contain '='."""
    meta = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key:
            raise ConfigError(f"--meta {item!r} must look like key=value")
        meta[key] = value
    return meta


def add_recorder_args(parser: argparse.ArgumentParser, out_flag: bool = True) -> None:
    """Recorder options (shared with ``papf record``)."""
    if out_flag:
        parser.add_argument("--out", required=True, metavar="F.mcap", help="recording to write")
    parser.add_argument("--keys", metavar="EXPR",
                        help="key expression to record (default: <namespace>/**)")
    parser.add_argument("--meta", action="append", default=[], metavar="KEY=VALUE",
                        help="run metadata (world, planner, seed, ...), repeatable")
    parser.add_argument("--compression", choices=sorted(COMPRESSIONS), default="zstd",
                        help="chunk compression (default: zstd)")
    parser.add_argument("--flush-interval", type=float, default=FLUSH_INTERVAL_S, metavar="S",
                        help=f"flush to disk at least this often [s] (default {FLUSH_INTERVAL_S})")
    parser.add_argument("--log-level", default="INFO")


def main(args: argparse.Namespace) -> int:
    """Run the recorder until SIGINT/SIGTERM; 0 on a clean stop, 2 on a bad setting."""
    log = setup_logging(NAME, args.log_level)
    try:
        meta = parse_meta(args.meta)
        with open_node(NAME, args, log) as node:
            record(node, args.out, args.keys or f"{args.namespace}/**", meta,
                   args.compression, args.flush_interval)
    except PapfError as exc:
        log.error("%s", exc)
        return 2
    return 0


if __name__ == "__main__":
    parser = argparse.ArgumentParser(prog="python -m nodes.recorder",
                                     description=__doc__.splitlines()[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter,
                                     epilog=describe(PORTS, VARIANTS))
    add_recorder_args(parser)
    add_zenoh_args(parser)
    raise SystemExit(main(parser.parse_args()))
