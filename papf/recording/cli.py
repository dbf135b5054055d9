"""``papf record | replay | recover | info`` (DESIGN.md §10). Wire with ``register(subparsers)``.

Each subcommand stores its handler as ``args.func``; the handler returns the exit
code (0 done, 2 bad input or unreadable recording, 130 interrupted).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from common.errors import PapfError
from common.transport import StopRequested, add_zenoh_args, config_from_args
from papf.recording.reader import Recording
from papf.recording.recover import recover
from papf.recording.replay import replay
from papf.viewer_cli import add_view_flag, replay_with_view


def register(subparsers) -> None:
    """Add ``record``, ``replay``, ``recover`` and ``info`` to an argparse subparsers object."""
    from nodes.recorder.__main__ import add_recorder_args  # the node owns its options

    p = subparsers.add_parser("record", help="record every message of a namespace into an MCAP",
                              description="Record until Ctrl-C (the file is then complete).")
    p.add_argument("out", metavar="F.mcap", help="recording to write")
    add_recorder_args(p, out_flag=False)
    add_zenoh_args(p)
    p.set_defaults(func=cmd_record)

    p = subparsers.add_parser("replay", help="republish a recording with its timing",
                              description="Republish a recording on its keys, in log-time "
                              "order, with the recorded timing scaled by --rate.")
    p.add_argument("file", metavar="F.mcap")
    p.add_argument("--rate", type=float, default=1.0,
                   help="speed factor; 0 = as fast as possible (default 1)")
    p.add_argument("--keys", action="append", metavar="EXPR",
                   help="replay only keys matching this key expression, repeatable (default all)")
    add_zenoh_args(p)
    add_view_flag(p)
    # --namespace from add_zenoh_args: here it remaps; unset = the recorded keys as they are.
    p.set_defaults(func=cmd_replay, namespace=None)

    p = subparsers.add_parser("recover", help="salvage a truncated recording",
                              description="Copy every complete message of a cut-short MCAP "
                              "into a new, valid file.")
    p.add_argument("broken", metavar="BROKEN.mcap")
    p.add_argument("fixed", metavar="FIXED.mcap", nargs="?",
                   help="output (default: BROKEN.recovered.mcap)")
    p.add_argument("--json", action="store_true", help="print the figures as JSON")
    p.set_defaults(func=cmd_recover)

    p = subparsers.add_parser("info", help="what a recording holds")
    p.add_argument("file", metavar="F.mcap")
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=cmd_info)


def cmd_record(args: argparse.Namespace) -> int:
    from nodes.recorder.__main__ import main as recorder_main

    return recorder_main(args)


def cmd_replay(args: argparse.Namespace) -> int:
    if args.view is not None:
        return replay_with_view(args, _replay)
    return _replay(args, StopRequested())


def _replay(args: argparse.Namespace, stop: StopRequested) -> int:
    import zenoh

    try:
        with zenoh.open(config_from_args(args)) as session:
            stats = replay(args.file, session, args.rate or None, args.keys, args.namespace,
                           progress=_progress_printer(), stop=lambda: bool(stop))
    except PapfError as exc:
        print(f"papf replay: {exc}", file=sys.stderr)
        return 2
    print(f"replayed {stats.messages} messages ({stats.log_span_s:.2f} s of recorded time) "
          f"in {stats.wall_s:.2f} s", file=sys.stderr)
    return 130 if stop else 0


def _progress_printer():
    """``progress(done, total)`` that rewrites one status line on a terminal, else stays quiet."""
    if not sys.stderr.isatty():
        return None

    def show(done: int, total: int) -> None:
        print(f"\rreplay {done}/{total} messages", end="", file=sys.stderr, flush=True)
        if done >= total:
            print(file=sys.stderr)

    return show


def cmd_recover(args: argparse.Namespace) -> int:
    broken = Path(args.broken)
    fixed = Path(args.fixed) if args.fixed else broken.with_suffix(".recovered.mcap")
    try:
        stats = recover(broken, fixed)
    except PapfError as exc:
        print(f"papf recover: {exc}", file=sys.stderr)
        return 2
    if args.json:
        print(json.dumps({"output": str(fixed), "messages": stats.messages,
                          "log_span_s": stats.log_span_s, "receive_span_s": stats.receive_span_s,
                          "channels": stats.channels, "complete": stats.complete,
                          "skipped_chunks": stats.skipped_chunks, "stopped_at": stats.stopped_at}))
    else:
        print(f"{fixed}: {stats.summary()}")
    return 0


def cmd_info(args: argparse.Namespace) -> int:
    try:
        with Recording(args.file) as rec:
            first, last = rec.time_span_ns()
            info = {"file": args.file, "metadata": rec.metadata, "messages": rec.counts(),
                    "first_log_ns": first, "last_log_ns": last}
    except PapfError as exc:
        print(f"papf info: {exc}", file=sys.stderr)
        return 2
    if args.json:
        print(json.dumps(info, indent=2))
        return 0
    print(f"{args.file}: log time {first / 1e9:.3f} .. {last / 1e9:.3f} s")
    for name, meta in info["metadata"].items():
        print(f"  metadata {name}: " + ", ".join(f"{k}={v}" for k, v in meta.items()))
    for key, n in sorted(info["messages"].items()):
        print(f"  {key:<40} {n:>8}")
    return 0
