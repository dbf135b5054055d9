"""Recorder node: every sample under a key expression into a crash-safe MCAP (docs/recording.md).

    python -m nodes.recorder --out run.mcap [--keys 'rosbot/**'] [--meta world=energy ...]

Ports: :mod:`nodes.recorder.ports` (``--help`` prints them); liveliness ``<ns>/alive/recorder``.

Samples are triaged on Zenoh's receive thread (:class:`Intake`: this run's seal, then the
per-key budgets of :mod:`nodes.recorder.budget` — a few look-ups, no decoding), queued, and
drained in batches by the main thread into :class:`nodes.recorder.writer.RunWriter`, which
flushes at least every ``--flush-interval`` seconds. SIGINT/SIGTERM: drain the queue, write the summary and footer, exit 0.
With ``--close-on-run-ended`` (the launch profiles that drive a run): the launcher's
``run_ended`` closes the file the same way (once the samples of its instant still on
their way are in: :mod:`nodes.recorder.tail`), and a ``recording_closed`` event (detail: the
file) tells the launcher it may stop the processes — no fixed wait, no lost tail.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import queue
import time
from collections import Counter
from pathlib import Path

import zenoh

from common.cliparse import ArgumentParser
from common.errors import ConfigError, PapfError, RecordingError
from common.outfiles import check_output
from common.params import arg_type, num
from common.ports import describe, plain
from common.transport import (
    Node,
    add_zenoh_args,
    alive_nodes,
    attachment_of,
    direct,
    open_node,
    setup_logging,
)
from nodes.recorder.budget import Budget
from nodes.recorder.ports import PORTS, VARIANTS
from nodes.recorder.ros2_bag import FORMATS, Ros2BagWriter, check_bag_dir
from nodes.recorder.tail import TAIL_MAX_S, RunEndWatch
from nodes.recorder.writer import COMPRESSIONS, FLUSH_INTERVAL_S, RunWriter, WriterStats
from schemas.messages import Event

NAME = "recorder"
BATCH = 5_000               # [samples] drained between stop/flush checks
IDLE_WAIT_S = 0.01           # [s] sleep when the queue is empty (the FIFO holds the backlog)
FINAL_DRAIN_S = 2.0         # [s] at most spent draining the queue after a stop request
STATUS_EVERY_S = 10.0       # [s] wall time between progress log lines


class Intake:
    """What reaches the writer (docs/recording.md "Bounds"), decided on Zenoh's thread:

    1. with the run's key (a recorder started by a launcher), only samples sealed by this
       run's processes (:mod:`common.seal`): a keyless peer's, a replay, another run's are
       counted per key and reason and never written — checked first, so that a flood of
       them spends no key's budget;
    2. then the per-key budgets of :class:`nodes.recorder.budget.Budget`.

    Admitted samples wait in a queue the main thread drains (:func:`drain`); nothing else
    runs here.
    """

    def __init__(self, node: Node, budget: Budget | None = None):
        self.trust, self.budget = node.trust, budget or Budget()
        self.queue: queue.SimpleQueue = queue.SimpleQueue()
        self.refused: Counter[tuple[str, str]] = Counter()
        self.ns = node.keys.ns

    def on_sample(self, sample: zenoh.Sample) -> None:
        if sample.kind != zenoh.SampleKind.PUT:   # a DELETE has no payload to record
            return
        key, zb = str(sample.key_expr), sample.payload
        if self.trust.keyed:
            payload = zb.to_bytes()
            verdict = self.trust.check(key, key, payload, attachment_of(sample))
            if verdict != "ok":
                self.refused[(key, verdict)] += 1
                return
        if self.budget.admit(key, len(zb)):
            return
        payload = payload if self.trust.keyed else zb.to_bytes()
        self.queue.put((key, payload, time.time_ns()))

    def dropped(self) -> dict[str, dict[str, int]]:
        """``{key: {reason: n}}``: refused seals and budget drops together."""
        out = self.budget.counts()
        for (key, why), n in list(self.refused.items()):
            out.setdefault(key, {})[why] = n
        return out


def drain(intake: Intake, writer: RunWriter, max_samples: int, watch: RunEndWatch | None = None) -> int:
    """Write up to ``max_samples`` queued samples; returns how many were taken.

    The hot loop of the recorder: locals only, one ``get_nowait`` per sample.
    """
    get, write = intake.queue.get_nowait, writer.write
    arrived = watch.arrived if watch is not None else None
    taken: dict[str, int] = {}   # bytes per key, handed back to the budget once per batch
    n = 0
    while n < max_samples:
        try:
            key, payload, t = get()
        except queue.Empty:
            break
        n += 1
        taken[key] = taken.get(key, 0) + len(payload)
        write(key, payload, t)
        if arrived is not None:
            arrived(key, payload, t)
    for key, nbytes in taken.items():
        intake.budget.written(key, nbytes)
    return n


def record(node: Node, out: str | Path, keys_expr: str, metadata: dict[str, str],
           compression: str = "zstd", flush_interval_s: float = FLUSH_INTERVAL_S,
           close_on_run_ended: bool = False,
           force: bool = False, announce: bool = False, fmt: str = "mcap",
           duration_s: float = 0.0) -> WriterStats:
    """Record until ``node.stop`` (or, with ``close_on_run_ended``, until the launcher's
    ``run_ended``); returns the writer's counts. The file is complete on return. ``fmt``:
    ``mcap`` (every message, ours) or ``ros2`` (a rosbag2 of the face's topics:
    :mod:`nodes.recorder.ros2_bag`).
    ``announce`` (``papf record`` by hand): say which nodes of the namespace are alive, or
    that it waits for the stack, and when the first message came."""
    watch = RunEndWatch(node.keys.events) if close_on_run_ended else None
    meta = {"namespace": node.keys.ns, "keys": keys_expr, **metadata}
    run = node.trust.run_hex()
    if run:
        meta["run_id"] = run   # only this run's samples are in it (Intake)
    intake = Intake(node)
    writer_cls = Ros2BagWriter if fmt == "ros2" else RunWriter
    with writer_cls(out, meta, compression=compression, flush_interval_s=flush_interval_s,
                    force=force) as writer:
        node.extra_health["recording"] = account(out, writer, intake, complete=False)
        sub = node.session.declare_subscriber(keys_expr, direct(intake.on_sample))
        try:
            node.ready()
            node.log.info("recording %s into %s", keys_expr, out)
            if announce:
                _announce(node, metadata)
            _loop(node, intake, writer, watch, duration_s)
            if watch is not None and watch.seen:
                _tail(node, intake, writer, watch)
            sub.undeclare()   # nothing more comes in: the queue can be emptied
            deadline = time.monotonic() + FINAL_DRAIN_S
            while drain(intake, writer, BATCH, watch) and time.monotonic() < deadline:
                pass
            writer.dropped_by_key = intake.dropped()
            writer.close()
            node.extra_health["recording"] = account(out, writer, intake, complete=True)
        except OSError as exc:   # the disk is full (or gone): stop, keep what is written
            writer.abandon()
            raise RecordingError(
                f"cannot write {out} ({exc.strerror or exc}) after {writer.stats.messages} "
                f"messages: the recording stops here; salvage it with: papf recover {out} "
                "FIXED.mcap") from None
        finally:
            with contextlib.suppress(Exception):   # undeclared twice: Zenoh says so, harmless
                sub.undeclare()
    node.log.info("closed %s: %d messages, %d bytes, %d channels", out, writer.stats.messages,
                  writer.stats.bytes, writer.stats.channels)
    if writer.stats.dropped and fmt == "ros2":
        node.log.info("%d messages not on the ROS 2 face (events, statuses…) left out of the "
                      "rosbag2 (--format mcap keeps everything)", writer.stats.dropped)
    elif writer.stats.dropped:
        node.log.warning("dropped %d messages on %d keys beyond %d channels", writer.stats.dropped,
                         writer.stats.dropped_keys, writer.stats.channels)
    if writer.dropped_by_key:
        node.log.warning("not recorded (refused or over budget), per key: %s",
                         writer.dropped_by_key)
    return writer.stats


def account(out, writer: RunWriter, intake: Intake, complete: bool) -> dict:
    """The recording as the launcher reports it (``papf run --json`` ``recording``)."""
    return {"file": str(out), "complete": complete, "messages": writer.stats.messages,
            "bytes": writer.stats.bytes, "dropped": intake.dropped()}


def _tail(node: Node, intake: Intake, writer: RunWriter, watch: RunEndWatch) -> None:
    """After run_ended: the samples of its instant still on other links (nodes.recorder.tail)."""
    deadline = time.monotonic() + TAIL_MAX_S
    while not watch.complete and not node.stop and time.monotonic() < deadline:
        if drain(intake, writer, BATCH, watch) == 0:
            node.stop.wait(IDLE_WAIT_S)
    if not watch.complete:
        node.log.warning("run_ended: closing without a sample of its instant on %s",
                         ", ".join(sorted(watch.waiting)))


def _announce(node: Node, metadata: dict[str, str]) -> None:
    """What a recording started by hand will hold: the namespace's nodes alive now (or none
    yet: it waits for the stack), and what its report will not know without ``--meta``."""
    alive = sorted(alive_nodes(node.session, node.keys) - {NAME, node.name})
    if alive:
        node.log.info("namespace %r: %s alive; recording from now (a run already going is "
                      "recorded from its middle)", node.keys.ns, ", ".join(alive))
    else:
        node.log.warning("namespace %r: no node alive yet; waiting for the stack (papf run "
                         "--realtime, papf launch ...) and recording from its first message "
                         "(wrong namespace? --namespace)", node.keys.ns)
    if "world" not in metadata:
        node.log.info("no --meta world=W: papf report will name the world 'unknown' "
                      "(--meta world=W --meta planner=P --meta seed=S say what ran)")


def _loop(node: Node, intake: Intake, writer: RunWriter, watch: RunEndWatch | None,
          duration_s: float = 0.0) -> None:
    """Record until stopped, the run ended (``watch``) or ``duration_s`` [s] passed (0: no
    limit)."""
    started = time.monotonic()
    until = started + duration_s if duration_s > 0 else math.inf
    next_status = started + STATUS_EVERY_S
    last_count, first = 0, True
    while not node.stop and not (watch and watch.seen) and time.monotonic() < until:
        if drain(intake, writer, BATCH, watch) == 0:
            writer.maybe_flush()
            node.stop.wait(IDLE_WAIT_S)
        elif first:
            first = False
            node.log.info("first messages after %.1f s", time.monotonic() - started)
        if time.monotonic() >= next_status:
            count = writer.stats.messages
            if count == 0:
                node.log.warning("no message in %.0f s: is a stack running in namespace %r?",
                                 time.monotonic() - started, node.keys.ns)
            else:
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
        parser.add_argument("--close-on-run-ended", action="store_true",
                            help="close the file at the launcher's run_ended, then publish a "
                                 "recording_closed event (the launcher waits for it)")
        parser.add_argument("--name", default=NAME,
                            help=f"node name (liveliness <ns>/alive/NAME; default {NAME}): the "
                                 "robot's black box is robot_recorder, beside the laptop's")
    parser.add_argument("--force", action="store_true",
                        help="replace the recording if it exists (default: refuse)")
    parser.add_argument("--keys", metavar="EXPR",
                        help="key expression to record (default: <namespace>/**)")
    parser.add_argument("--meta", action="append", default=[], metavar="KEY=VALUE",
                        help="run metadata (world, planner, seed, ...), repeatable")
    parser.add_argument("--format", choices=FORMATS, default="mcap",
                        help="mcap (default: every message, ours) or ros2 (a rosbag2 directory "
                             "of the ROS 2 face's topics: ros2 bag, RViz, papf report)")
    parser.add_argument("--duration", type=arg_type("--duration", num(0.0, 1e6, "s")), default=0.0, metavar="S",
                        help="stop after S seconds of wall time, the file complete (default 0: "
                             "until Ctrl-C)")
    parser.add_argument("--compression", choices=sorted(COMPRESSIONS), default="zstd",
                        help="chunk compression (default: zstd)")
    parser.add_argument("--flush-interval", type=float, default=FLUSH_INTERVAL_S, metavar="S",
                        help=f"flush to disk at least this often [s] (default {FLUSH_INTERVAL_S})")
    parser.add_argument("--log-level", default="INFO")


def main(args: argparse.Namespace) -> int:
    """Run the recorder until SIGINT/SIGTERM; 0 on a clean stop, 2 on a bad setting."""
    name = getattr(args, "name", NAME)
    log = setup_logging(name, args.log_level)
    try:
        meta = parse_meta(args.meta)
        fmt = getattr(args, "format", "mcap")
        if fmt == "ros2":   # before the bus: refuse at once
            check_bag_dir(args.out, args.force)
        else:
            check_output(args.out, force=args.force)
        with open_node(name, args, log) as node:
            close = getattr(args, "close_on_run_ended", False)
            if close:
                node.declare_publishers("events")   # up front: the one put must not be late
            record(node, args.out, args.keys or f"{args.namespace}/**", meta,
                   args.compression, args.flush_interval, close_on_run_ended=close,
                   force=args.force, announce=not close, fmt=fmt,
                   duration_s=getattr(args, "duration", 0.0))
            if close and not node.stop:   # the file is closed: say so, then wait to be stopped
                node.publish("events", Event(stamp_ns=0, kind="recording_closed", source=name,
                                             detail=str(args.out)))
                while not node.stop.wait(1.0):
                    pass
    except PapfError as exc:
        log.error("%s", exc)
        return 2
    return 0


if __name__ == "__main__":
    parser = ArgumentParser(prog="python -m nodes.recorder",
                                     description=plain(__doc__.splitlines()[0]),
                                     formatter_class=argparse.RawDescriptionHelpFormatter,
                                     epilog=describe(PORTS, VARIANTS))
    add_recorder_args(parser)
    add_zenoh_args(parser)
    raise SystemExit(main(parser.parse_args()))
