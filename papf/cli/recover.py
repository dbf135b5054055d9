"""``papf recover BROKEN.mcap [FIXED.mcap]``: salvage a truncated recording (:mod:`papf.recording.recover`)."""

from __future__ import annotations

import json
from pathlib import Path

from common.errors import PapfError
from common.text import print_error


def register(sub) -> None:
    """Add ``papf recover`` and its options to the subcommands ``sub``."""
    p = sub.add_parser("recover", help="salvage a truncated recording",
                       description="Copy every intact message of a cut-short or damaged "
                                   "MCAP into a new, valid file, and say what was lost.")
    p.add_argument("broken", metavar="BROKEN.mcap")
    p.add_argument("fixed", metavar="FIXED.mcap", nargs="?",
                   help="output (default: BROKEN.recovered.mcap)")
    p.add_argument("--json", action="store_true", help="print the figures as JSON")
    p.add_argument("--force", action="store_true", help="replace FIXED.mcap if it exists")
    p.set_defaults(func=cmd_recover)


def cmd_recover(args) -> int:
    """``papf recover``: salvage a truncated recording into a new file; the exit code."""
    from papf.recording.recover import recover  # mcap: only when recovering

    broken = Path(args.broken)
    fixed = Path(args.fixed) if args.fixed else broken.with_suffix(".recovered.mcap")
    try:
        stats = recover(broken, fixed, force=args.force)
    except PapfError as exc:
        print_error("papf recover", str(exc))
        return 2
    if args.json:
        print(json.dumps(stats.to_json(str(fixed))))
    else:
        print(f"{fixed}: {stats.summary()}")
    return 0
