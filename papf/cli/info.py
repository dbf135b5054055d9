"""``papf info F.mcap|BAG``: what a recording holds (metadata, messages per key, time span);
of a rosbag2: its topics, and which of them ``papf report`` reads as what (``--topics``)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

from common.errors import ConfigError, PapfError
from common.text import print_error, safe_text


def register(sub) -> None:
    """Add ``papf info`` and its options to the subcommands ``sub``."""
    from papf.cli.report import add_topics_option

    p = sub.add_parser("info", help="what a recording (or a rosbag2 from the robot) holds")
    p.add_argument("file", metavar="F.mcap|BAG")
    p.add_argument("--json", action="store_true")
    add_topics_option(p)
    p.set_defaults(func=cmd_info)


def cmd_info(args) -> int:
    """What the summary says, and whether the data holds it: every chunk's CRC is checked."""
    from papf.cli.report import topic_map
    from papf.recording.reader import Recording  # mcap: only when reading
    from papf.recording.rosbag import is_rosbag
    from papf.recording.scan import scan_file

    if is_rosbag(args.file, topic_map(args)):
        return _bag_info(args)
    try:
        with Recording(args.file) as rec:
            first, last = rec.time_span_ns()
            channels = rec.channels()
            info = {"file": args.file, "metadata": rec.metadata, "messages": rec.counts(),
                    "channels": {k: {"schema": s, "schema_encoding": se, "message_encoding": me}
                                 for k, (s, se, me) in channels.items()},
                    "first_log_ns": first, "last_log_ns": last}
        scan, intact = scan_file(args.file)
    except PapfError as exc:
        print_error("papf info", str(exc))
        return 2
    info.update(intact_messages=intact, damaged_chunks=scan.bad_chunks,
                damaged_bytes=scan.damaged_bytes)
    if args.json:
        print(json.dumps(info, indent=2))
    else:
        _print_info(args.file, info, channels, first, last)
    if scan.damaged:
        total = sum(info["messages"].values())
        print(f"papf info: {args.file} is damaged: {scan.bad_chunks} chunk(s) fail their "
              f"CRC, {scan.damaged_bytes} bytes unreadable; {total - intact} of {total} "
              f"messages are lost. Salvage the rest with: papf recover {args.file} FIXED.mcap",
              file=sys.stderr)
        return 2
    return 0


def _print_info(file, info: dict, channels: dict, first: int, last: int) -> None:
    # keys, metadata and schema names are whatever a peer put on the bus: shown, never run
    # (common.text), and a key of megabytes stays one short line
    print(f"{safe_text(str(file))}: log time {first / 1e9:.3f} .. {last / 1e9:.3f} s")
    for name, meta in info["metadata"].items():
        print(f"  metadata {safe_text(name, 80)}: "
              + ", ".join(f"{safe_text(k, 80)}={safe_text(v)}" for k, v in meta.items()))
    # every field shown (each value as a value: a peer's 5 KB note is cut, the line is not)
    shown = {k: safe_text(k, 120) for k in channels}
    width = max((len(k) for k in shown.values()), default=10)
    print(f"  {'KEY':<{width}} {'MESSAGES':>8}  {'SCHEMA':<24} ENCODING (message / schema)")
    for key, (schema, schema_enc, msg_enc) in sorted(channels.items()):
        n = info["messages"].get(key, 0)
        enc = f"{msg_enc} / {schema_enc}" if schema_enc else f"{msg_enc} / no schema (raw)"
        print(f"  {shown[key]:<{width}} {n:>8}  {safe_text(schema or '-', 60):<24} "
              f"{safe_text(enc, 80)}")


def _bag_info(args) -> int:
    """A rosbag2: storage, span, every topic with its type and count, and the roles read."""
    from dataclasses import asdict

    from papf.cli.report import topic_map
    from papf.recording.rosbag import BagRecording

    topics = topic_map(args)
    try:
        with BagRecording(args.file, topics) as bag:
            first, last = bag.time_span_ns()
            info = {"file": args.file, "rosbag2": True, "duration_s": (last - first) / 1e9,
                    "topics": {t: {"type": m, "messages": n}
                               for t, (m, n) in bag.bag_topics().items()},
                    "roles": asdict(bag.topics), "as_our_keys": bag.counts()}
    except ConfigError as exc:   # topics not the ROSbot's: still say what the bag holds
        info = _plain_bag(args.file)
        print_error("papf info", f"{exc} (papf report and replay need that)")
    if args.json:
        print(json.dumps(info, indent=2))
        return 0
    print(f"{args.file}: rosbag2, {info['duration_s']:.3f} s")
    role_of = {t: r for r, t in info["roles"].items()}
    shown = {t: safe_text(t, 120) for t in info["topics"]}   # a bag's names: shown, never run
    width = max((len(t) for t in shown.values()), default=10)
    types = {t: safe_text(d["type"], 80) for t, d in info["topics"].items()}
    tw = max((len(v) for v in types.values()), default=4)
    print(f"  {'TOPIC':<{width}} {'MESSAGES':>8}  {'TYPE':<{tw}} READ AS")
    for t, d in sorted(info["topics"].items()):
        print(f"  {shown[t]:<{width}} {d['messages']:>8}  {types[t]:<{tw}} {role_of.get(t, '-')}")
    return 0


def _plain_bag(path: str) -> dict:
    """A rosbag2's topics, types, counts and span as rosbags reads them, no role read."""
    from rosbags.highlevel import AnyReader

    from common.errors import RecordingError

    try:
        with AnyReader([Path(path)]) as reader:
            topics: dict[str, dict] = {}
            for c in reader.connections:
                d = topics.setdefault(c.topic, {"type": c.msgtype, "messages": 0})
                d["messages"] += c.msgcount
            span = (reader.end_time - reader.start_time) / 1e9 if reader.connections else 0.0
    except Exception as exc:   # rosbags raises its own errors for unreadable bags
        raise RecordingError(f"{path}: not a readable rosbag2 ({exc})") from None
    return {"file": path, "rosbag2": True, "duration_s": span, "topics": topics, "roles": {},
            "as_our_keys": {}}
