"""``papf export foxglove IN.mcap OUT.mcap``: a recording as the live view's Foxglove
channels (:mod:`papf.recording.foxglove_export`; why an export: docs/recording.md)."""

from __future__ import annotations

import argparse
import sys


def register(sub) -> None:
    p = sub.add_parser("export", help="convert a recording for another tool")
    formats = p.add_subparsers(dest="format", required=True, metavar="FORMAT")
    f = formats.add_parser("foxglove", help="a recording as Foxglove's own channels (MCAP)",
                           description="Write OUT.mcap with the live view's channels "
                           "(LaserScan, FrameTransforms, PoseInFrame, SceneUpdate, Log, JSON "
                           "plots), JSON with Foxglove's JSON Schemas; Foxglove opens it.")
    f.add_argument("src", metavar="IN.mcap")
    f.add_argument("dst", metavar="OUT.mcap")
    f.add_argument("--world", help="world to draw (default: the recording's metadata)")
    f.add_argument("--force", action="store_true", help="replace OUT.mcap if it exists")
    f.set_defaults(func=cmd_export_foxglove)


def cmd_export_foxglove(args: argparse.Namespace) -> int:
    from papf.recording.foxglove_export import export_foxglove

    stats = export_foxglove(args.src, args.dst, args.world, force=args.force)
    for note in stats.notes:
        print(f"papf export: {note}", file=sys.stderr)
    print(f"{args.dst}: {stats.written} Foxglove messages from {stats.read} recorded "
          f"({stats.skipped} skipped), world {stats.world or 'none'}")
    return 0
