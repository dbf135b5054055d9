"""Tracker node: ``python -m nodes.tracker [--realtime] [--set name=value]``.

Turns LiDAR scans into tracked obstacles (:mod:`nodes.tracker.core`: scan-order
clustering, Hungarian association, constant-velocity Kalman filter), so a planner gets
the same ``Objects`` from a real sensor as from the sim's ground truth.

Ports: :mod:`nodes.tracker.ports` (``--help`` prints them).

Settings: ``--realtime`` (pair each scan with the latest pose instead of the same
stamp), ``--pair-timeout S``, ``--set name=value`` (any field of
:class:`nodes.tracker.core.TrackerParams`, e.g. ``--set gate=0.6``), plus the Zenoh
options. Exit code 2 on a bad setting.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time

from common.cliparse import ArgumentParser
from common.drive import PAIR_TIMEOUT
from common.errors import ConfigError
from common.params import arg_type
from common.ports import describe
from common.transport import add_zenoh_args, exit_fast, open_node, setup_logging
from common.units import LOCKSTEP_PAIR_TIMEOUT_S
from nodes.tracker.core import Tracker, TrackerParams
from nodes.tracker.loop import TrackerLoop
from nodes.tracker.ports import PORTS, VARIANTS

NODE_NAME = "tracker"


def params_from(items: list[str]) -> TrackerParams:
    """``["gate=0.6", ...]`` -> TrackerParams; ConfigError names a bad item and the valid names."""
    fields = {f.name: f for f in dataclasses.fields(TrackerParams)}
    values = {}
    for item in items:
        name, sep, text = item.partition("=")
        if not sep or name not in fields:
            raise ConfigError(f"--set {item!r}: expected NAME=VALUE with NAME one of "
                              f"{', '.join(fields)}")
        kind = type(fields[name].default)
        try:
            if kind is bool:
                if text.lower() not in ("true", "false", "1", "0"):
                    raise ValueError(text)
                values[name] = text.lower() in ("true", "1")
            else:
                values[name] = kind(text)
        except ValueError:
            raise ConfigError(f"--set {item!r}: {text!r} is not a {kind.__name__}") from None
    return TrackerParams(**values)


def run(args: argparse.Namespace, params: TrackerParams) -> int:
    """Run the tracker node until stopped; the process's exit code."""
    log = setup_logging(NODE_NAME, args.log_level)
    tracker = Tracker(params)
    tracker.warm_up()                      # JIT-compile before ready, not in the first cycle
    loop = TrackerLoop(tracker, args.realtime, args.pair_timeout)
    with open_node(NODE_NAME, args, log) as node:
        for _, topic, _ in (p for p in PORTS if p[0] == "in"):
            node.subscribe(topic)
        node.declare_publishers(*(topic for d, topic, _ in PORTS if d == "out"))
        node.ready()
        for topic, msg in node.messages(tick_s=0.05):
            now = time.monotonic()
            out = loop.on_message(topic, msg, now) if topic else loop.poll(now)
            for out_topic, out_msg in out:
                node.publish(out_topic, out_msg)
        log.info("stopping after %d cycles (%d without their own pose)", loop.cycles,
                 loop.unpaired)
    return 0


def main(argv: list[str] | None = None) -> int:
    """``python -m nodes.tracker``: run the node; the exit code (2 on a bad setting)."""
    parser = ArgumentParser(prog="python -m nodes.tracker",
                                     description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter,
                                     epilog=__doc__.split("\n\n", 1)[1] + "\n\n"
                                     + describe(PORTS, VARIANTS))
    parser.add_argument("--realtime", action="store_true",
                        help="pair each scan with the latest pose (robot / HIL)")
    parser.add_argument("--pair-timeout", type=arg_type("--pair-timeout", PAIR_TIMEOUT),
                        default=LOCKSTEP_PAIR_TIMEOUT_S, metavar="S",
                        help="lockstep: wall time a scan waits for its pose [s] (default "
                             f"{LOCKSTEP_PAIR_TIMEOUT_S:g}, longer than the driver's "
                             "--lockstep-timeout)")
    parser.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                        help="override a tracker setting, repeatable")
    parser.add_argument("--log-level", default="INFO")
    add_zenoh_args(parser)
    args = parser.parse_args(argv)
    try:
        params = params_from(args.set)
    except ConfigError as exc:
        print(f"tracker: {exc}", file=sys.stderr)
        return 2
    return run(args, params)


if __name__ == "__main__":
    exit_fast(main())   # the session is closed: skip the interpreter's slow teardown
