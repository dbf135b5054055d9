"""``papf replay F.mcap``: republish a recording on its keys with its timing (:mod:`papf.recording.replay`)."""

from __future__ import annotations

import sys

from common.errors import PapfError
from common.transport import StopRequested, add_zenoh_args, config_from_args
from papf.cli.view import add_view_flag


def register(sub) -> None:
    p = sub.add_parser("replay", help="republish a recording with its timing",
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


def cmd_replay(args) -> int:
    if args.view is not None:
        from papf.replay_view import replay_with_view

        return replay_with_view(args, _replay)
    return _replay(args, StopRequested())


def _replay(args, stop: StopRequested) -> int:
    import zenoh  # the session: only when replaying

    from papf.progress import DecileProgress
    from papf.recording.replay import replay

    try:
        with zenoh.open(config_from_args(args)) as session, DecileProgress("replay") as bar:
            stats = replay(args.file, session, args.rate or None, args.keys, args.namespace,
                           progress=_progress_printer(bar), stop=lambda: bool(stop))
    except PapfError as exc:
        print(f"papf replay: {exc}", file=sys.stderr)
        return 2
    print(f"replayed {stats.messages} messages ({stats.log_span_s:.2f} s of recorded time) "
          f"in {stats.wall_s:.2f} s", file=sys.stderr)
    return 130 if stop else 0


def _progress_printer(bar):
    """``progress(done, total)`` feeding a :class:`papf.progress.DecileProgress`: a live bar
    on a terminal, else one line per 10 % of the messages."""
    def show(done: int, total: int) -> None:
        bar.fraction(done / total if total else 1.0, f"{done}/{total} messages")

    return show
