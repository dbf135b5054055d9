"""``papf view``: a namespace's traffic as a Foxglove WebSocket server (:mod:`nodes.viewer`);
``--view [PORT]`` of ``papf run | launch | replay`` (docs/viewer.md)."""

from __future__ import annotations

import argparse

from common.params import PORT, arg_type
from common.transport import add_zenoh_args

DEFAULT_VIEW_PORT = 8765


def add_view_flag(parser: argparse.ArgumentParser) -> None:
    """``--view [PORT]`` of ``papf run | launch | replay``."""
    parser.add_argument("--view", nargs="?", type=arg_type("--view", PORT), const=DEFAULT_VIEW_PORT,
                        metavar="PORT",
                        help=f"also serve a live Foxglove view on ws://127.0.0.1:PORT "
                             f"(default {DEFAULT_VIEW_PORT}; see docs/viewer.md)")


def register(sub) -> None:
    """Add ``papf view`` and its options to the subcommands ``sub``."""
    from nodes.viewer.__main__ import add_view_args

    p = sub.add_parser("view", help="serve a namespace's traffic to Foxglove (WebSocket)",
                       description="Subscribe to a namespace's keys and serve them as "
                       "Foxglove channels on ws://HOST:PORT until Ctrl-C. Open it in "
                       "Foxglove with docs/foxglove-layout.json.")
    add_view_args(p)
    p.add_argument("--layout", metavar="OUT.json",
                   help="write the Foxglove layout of the view (3D, plots, log, parameters) "
                        "to this file and exit (the repository has it: docs/foxglove-layout.json)")
    p.add_argument("--force", action="store_true", help="replace an existing --layout file")
    p.add_argument("--log-level", default="INFO")
    add_zenoh_args(p)
    p.set_defaults(func=cmd_view)


def cmd_view(args: argparse.Namespace) -> int:
    """``papf view``: serve a namespace to Foxglove (or write its layout); the exit code."""
    if args.layout:   # the one output rule (common/outfiles.py): --force to replace
        from common.outfiles import output
        from nodes.viewer.layout import layout_json

        with output(args.layout, force=args.force) as tmp:
            tmp.write_text(layout_json())
        print(f"wrote {args.layout}")
        return 0
    from common.transport import setup_logging
    from nodes.viewer.__main__ import serve

    return serve(args, setup_logging("viewer", args.log_level))
