"""``papf record F.mcap``: every message of a namespace into an MCAP, until Ctrl-C.

The options are the recorder node's own (:func:`nodes.recorder.__main__.add_recorder_args`).
"""

from __future__ import annotations

from common.transport import add_zenoh_args
from nodes.recorder.__main__ import add_recorder_args
from nodes.recorder.__main__ import main as recorder_main


def register(sub) -> None:
    """Add ``papf record`` and its options to the subcommands ``sub``."""
    p = sub.add_parser("record", help="record every message of a namespace into an MCAP",
                       description="Record until Ctrl-C or --duration S (the file is then complete).")
    p.add_argument("out", metavar="F.mcap", help="recording to write")
    add_recorder_args(p, out_flag=False)
    add_zenoh_args(p)
    p.set_defaults(func=cmd_record)


def cmd_record(args) -> int:
    """``papf record``: record a namespace until Ctrl-C; the exit code."""
    return recorder_main(args)
