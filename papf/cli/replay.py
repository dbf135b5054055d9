"""``papf replay F.mcap``: republish a recording on its keys with its timing (:mod:`papf.recording.replay`)."""

from __future__ import annotations

import sys

from common.errors import ConfigError, PapfError
from common.text import print_error, safe_line
from common.transport import (
    DEFAULT_ENDPOINT,
    StopRequested,
    add_zenoh_args,
    open_session,
)
from papf.cli.view import add_view_flag


def register(sub) -> None:
    """Add ``papf replay`` and its options to the subcommands ``sub``."""
    p = sub.add_parser("replay", help="republish a recording with its timing",
                       description="Republish a recording on its keys, in log-time "
                                   "order, with the recorded timing scaled by --rate.")
    from papf.cli.report import add_topics_option

    p.add_argument("file", metavar="F.mcap|BAG",
                   help="a recording, or a rosbag2 from the robot (replayed as our messages on "
                        "our keys: odom, wheels, battery/measured, cmd_vel, scan)")
    p.add_argument("--rate", type=float, default=1.0,
                   help="speed factor; 0 = as fast as possible (default 1)")
    p.add_argument("--keys", action="append", metavar="EXPR",
                   help="replay only keys matching this key expression, repeatable (default all)")
    p.add_argument("--into-live", action="store_true",
                   help="replay even where a live stack runs in the target namespace "
                        "(its nodes would act on the recorded messages)")
    add_topics_option(p)
    add_zenoh_args(p)
    add_view_flag(p)
    # --namespace from add_zenoh_args: here it remaps; unset = the recorded keys as they are.
    p.set_defaults(func=cmd_replay, namespace=None)


def cmd_replay(args) -> int:
    """``papf replay``: republish a recording with its timing; the exit code."""
    if args.view is not None:
        from papf.launch.replay_view import replay_with_view

        return replay_with_view(args, _replay)
    return _replay(args, StopRequested())


def _replay(args, stop: StopRequested) -> int:
    """Check the file, the rate and where it would publish before publishing anything."""
    from papf.cli.report import topic_map
    from papf.console.progress import DecileProgress
    from papf.recording.replay import check_rate, replay, target_namespaces
    from papf.recording.rosbag import open_run  # mcap, rosbags: only when replaying

    try:
        check_rate(args.rate)
        topics = topic_map(args)
        with open_run(args.file, topics) as rec:
            namespaces = target_namespaces(rec, args.keys, args.namespace)
        where = ", ".join(args.connect) or ("the --zenoh-config endpoints" if args.zenoh_config
                                             else DEFAULT_ENDPOINT)
        own = own_router(args)
        if own:   # as papf run does: nothing to connect to, so this process is the router
            args.mode, where = "router", ", ".join(own)
            args.listen = own
            print(f"papf replay: replaying through its own router on {where} (no router to "
                  "join; papf topic echo, papf view, papf record reach it there)",
                  file=sys.stderr)
        with open_session(args, where) as session, DecileProgress("replay") as bar:
            if not own:   # a router of our own has no one else on it
                _refuse_live(session, namespaces, args.into_live)
            print(f"papf replay: publishing {args.file} into the Zenoh router at {where}, "
                  f"namespace {', '.join(sorted(namespaces)) or '(none)'}", file=sys.stderr)
            stats = replay(args.file, session, args.rate or None, args.keys, args.namespace,
                           progress=_progress_printer(bar), stop=lambda: bool(stop),
                           topics=topics)
    except PapfError as exc:
        print_error("papf replay", str(exc))
        return 2
    print(f"replayed {stats.messages} messages ({stats.log_span_s:.2f} s of recorded time) "
          f"in {stats.wall_s:.2f} s", file=sys.stderr)
    if stats.skipped_keys:
        print(safe_line(f"papf replay: skipped {sum(stats.skipped_keys.values())} messages on "
                        f"recorded topics that are not Zenoh keys: "
                        f"{', '.join(sorted(stats.skipped_keys))}"), file=sys.stderr)
    return 130 if stop else 0


def own_router(args) -> list[str]:
    """The endpoints ``papf replay`` listens on as its own router (no ``--connect``, no
    ``--zenoh-config``, client mode): ``--listen``'s when given, else the default endpoint
    when nothing listens there; [] otherwise (it joins the router it reaches)."""
    from common.reach import accepts

    if args.mode != "client" or args.connect or args.zenoh_config:
        return []
    if args.listen:   # asked for: this replay is the router there
        return list(args.listen)
    return [] if accepts(DEFAULT_ENDPOINT) else [DEFAULT_ENDPOINT]


def passive_nodes() -> set[str]:
    """Nodes a replay cannot make act: those whose declared outputs (``nodes/<node>/ports.py``,
    every variant) are events alone — the recorder writes what it hears, it steers nothing —
    and the viewer (its goals come from a user; ``replay --view`` starts it refusing them)."""
    import importlib
    import pkgutil

    import nodes

    passive = {"viewer"}
    for info in pkgutil.iter_modules(nodes.__path__):
        try:
            ports = importlib.import_module(f"nodes.{info.name}.ports")
        except ImportError:
            continue
        declared = [*ports.PORTS, *(p for v in getattr(ports, "VARIANTS", {}).values()
                                    for p in (v if isinstance(v, tuple) else ()))]
        outs = {key for direction, key, *_ in declared if direction == "out"}
        if outs <= {"events"}:
            passive.add(info.name)
    return passive


def _refuse_live(session, namespaces: set[str], into_live: bool) -> None:
    """A live stack in a target namespace would act on recorded messages: refuse. Nodes that
    act on nothing (:func:`passive_nodes`: a lone recorder) are no live stack. One
    liveliness query for every namespace (a recording may name thousands)."""
    alive: dict[str, set[str]] = {}
    for reply in session.liveliness().get("**/alive/*", timeout=1.0):
        if reply.ok is not None:
            ns, _, name = str(reply.ok.key_expr).rpartition("/alive/")
            alive.setdefault(ns, set()).add(name)
    passive = passive_nodes()
    for ns in sorted(namespaces & set(alive)):
        live = alive[ns] - passive
        if live and not into_live:
            raise ConfigError(f"a live stack runs in namespace {ns!r} (alive: "
                              f"{', '.join(sorted(live))}); replaying would feed it recorded "
                              "messages. Replay under another --namespace, or give --into-live")


def _progress_printer(bar):
    """``progress(done, total)`` feeding a :class:`papf.console.progress.DecileProgress`: a live bar
    on a terminal, else one line per 10 % of the messages."""
    def show(done: int, total: int) -> None:
        bar.fraction(done / total if total else 1.0, f"{done}/{total} messages")

    return show
