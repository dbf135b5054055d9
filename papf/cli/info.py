"""``papf info F.mcap``: what a recording holds (metadata, messages per key, time span)."""

from __future__ import annotations

import json
import sys

from common.errors import PapfError


def register(sub) -> None:
    p = sub.add_parser("info", help="what a recording holds")
    p.add_argument("file", metavar="F.mcap")
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=cmd_info)


def cmd_info(args) -> int:
    from papf.recording.reader import Recording  # mcap: only when reading

    try:
        with Recording(args.file) as rec:
            first, last = rec.time_span_ns()
            channels = rec.channels()
            info = {"file": args.file, "metadata": rec.metadata, "messages": rec.counts(),
                    "channels": {k: {"schema": s, "schema_encoding": se, "message_encoding": me}
                                 for k, (s, se, me) in channels.items()},
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
    width = max((len(k) for k in channels), default=10)
    print(f"  {'KEY':<{width}} {'MESSAGES':>8}  {'SCHEMA':<24} ENCODING (message / schema)")
    for key, (schema, schema_enc, msg_enc) in sorted(channels.items()):
        n = info["messages"].get(key, 0)
        enc = f"{msg_enc} / {schema_enc}" if schema_enc else f"{msg_enc} / no schema (raw)"
        print(f"  {key:<{width}} {n:>8}  {schema or '-':<24} {enc}")
    return 0
