"""``papf record | replay | recover | info`` (DESIGN.md §10). Wire with ``register(subparsers)``.

Each subcommand stores its handler as ``args.func``; the handler returns the exit
code (0 done, 2 bad input or unreadable recording, 130 interrupted).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from common.errors import ConfigError, PapfError
from common.transport import (
    DEFAULT_ENDPOINT,
    StopRequested,
    add_zenoh_args,
    alive_nodes,
    open_session,
)
from papf.recording.reader import Recording
from papf.recording.recover import recover
from papf.recording.replay import check_rate, replay, target_namespaces
from papf.recording.scan import scan_file
from schemas import Keys


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
    p.add_argument("--into-live", action="store_true",
                   help="replay even where a live stack runs in the target namespace "
                        "(its nodes would act on the recorded messages)")
    add_zenoh_args(p)
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
    """Check the file, the rate and where it would publish before publishing anything."""
    stop = StopRequested()
    try:
        check_rate(args.rate)
        with Recording(args.file) as rec:
            namespaces = target_namespaces(rec, args.keys, args.namespace)
        where = ", ".join(args.connect) or ("the --zenoh-config endpoints" if args.zenoh_config
                                             else DEFAULT_ENDPOINT)
        with open_session(args, where) as session:
            _refuse_live(session, namespaces, args.into_live)
            print(f"papf replay: publishing {args.file} into the Zenoh router at {where}, "
                  f"namespace {', '.join(sorted(namespaces)) or '(none)'}", file=sys.stderr)
            stats = replay(args.file, session, args.rate or None, args.keys, args.namespace,
                           progress=_progress_printer(), stop=lambda: bool(stop))
    except PapfError as exc:
        print(f"papf replay: {exc}", file=sys.stderr)
        return 2
    print(f"replayed {stats.messages} messages ({stats.log_span_s:.2f} s of recorded time) "
          f"in {stats.wall_s:.2f} s", file=sys.stderr)
    if stats.skipped_keys:
        print(f"papf replay: skipped {sum(stats.skipped_keys.values())} messages on recorded "
              f"topics that are not Zenoh keys: {', '.join(sorted(stats.skipped_keys))}",
              file=sys.stderr)
    return 130 if stop else 0


def _refuse_live(session, namespaces: set[str], into_live: bool) -> None:
    """A live stack in a target namespace would act on recorded messages: refuse."""
    for ns in sorted(namespaces):
        try:
            alive = alive_nodes(session, Keys(ns))
        except ValueError:
            continue
        if alive and not into_live:
            raise ConfigError(f"a live stack runs in namespace {ns!r} (alive: "
                              f"{', '.join(sorted(alive))}); replaying would feed it recorded "
                              "messages. Replay under another --namespace, or give --into-live")


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
        print(json.dumps(stats.to_json(str(fixed))))
    else:
        print(f"{fixed}: {stats.summary()}")
    return 0


def cmd_info(args: argparse.Namespace) -> int:
    """What the summary says, and whether the data holds it: every chunk's CRC is checked."""
    try:
        with Recording(args.file) as rec:
            first, last = rec.time_span_ns()
            info = {"file": args.file, "metadata": rec.metadata, "messages": rec.counts(),
                    "first_log_ns": first, "last_log_ns": last}
        scan, intact = scan_file(args.file)
    except PapfError as exc:
        print(f"papf info: {exc}", file=sys.stderr)
        return 2
    info.update(intact_messages=intact, damaged_chunks=scan.bad_chunks,
                damaged_bytes=scan.damaged_bytes)
    damage = ""
    if scan.damaged:
        total = sum(info["messages"].values())
        damage = (f"papf info: {args.file} is damaged: {scan.bad_chunks} chunk(s) fail their "
                  f"CRC, {scan.damaged_bytes} bytes unreadable; {total - intact} of {total} "
                  f"messages are lost. Salvage the rest with: papf recover {args.file} FIXED.mcap")
    if args.json:
        print(json.dumps(info, indent=2))
    else:
        print(f"{args.file}: log time {first / 1e9:.3f} .. {last / 1e9:.3f} s")
        for name, meta in info["metadata"].items():
            print(f"  metadata {name}: " + ", ".join(f"{k}={v}" for k, v in meta.items()))
        for key, n in sorted(info["messages"].items()):
            print(f"  {key:<40} {n:>8}")
    if damage:
        print(damage, file=sys.stderr)
        return 2
    return 0
