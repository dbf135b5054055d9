"""``papf view | export foxglove | animate`` (docs/viewer.md). Wire with ``register(subparsers)``."""

from __future__ import annotations

import argparse
import sys

from common.transport import add_zenoh_args

DEFAULT_VIEW_PORT = 8765


def add_view_flag(parser: argparse.ArgumentParser) -> None:
    """``--view [PORT]`` of ``papf run | launch | replay``."""
    parser.add_argument("--view", nargs="?", type=int, const=DEFAULT_VIEW_PORT, metavar="PORT",
                        help=f"also serve a live Foxglove view on ws://127.0.0.1:PORT "
                             f"(default {DEFAULT_VIEW_PORT}; see docs/viewer.md)")


def viewer_argv(port: int, world: str | None, goals: str) -> list[str]:
    """Arguments of ``python -m nodes.viewer`` for a ``--view PORT`` (Zenoh options apart)."""
    argv = ["--port", str(port), "--goals", goals]
    return argv + (["--world", world] if world else [])


def register(subparsers) -> None:
    from nodes.viewer.__main__ import add_view_args

    p = subparsers.add_parser("view", help="serve a namespace's traffic to Foxglove (WebSocket)",
                              description="Subscribe to a namespace's keys and serve them as "
                              "Foxglove channels on ws://HOST:PORT until Ctrl-C. Open it in "
                              "Foxglove with docs/foxglove-layout.json.")
    add_view_args(p)
    p.add_argument("--layout", metavar="OUT.json",
                   help="write the Foxglove layout of the view (3D, plots, log, parameters) "
                        "to this file and exit (the repository has it: docs/foxglove-layout.json)")
    p.add_argument("--log-level", default="INFO")
    add_zenoh_args(p)
    p.set_defaults(func=cmd_view)

    p = subparsers.add_parser("export", help="convert a recording for another tool")
    sub = p.add_subparsers(dest="format", required=True, metavar="FORMAT")
    f = sub.add_parser("foxglove", help="a recording as Foxglove's own channels (MCAP)",
                       description="Write OUT.mcap with the live view's channels (LaserScan, "
                       "FrameTransforms, PoseInFrame, SceneUpdate, Log, JSON plots), JSON with "
                       "Foxglove's JSON Schemas; Foxglove opens it.")
    f.add_argument("src", metavar="IN.mcap")
    f.add_argument("dst", metavar="OUT.mcap")
    f.add_argument("--world", help="world to draw (default: the recording's metadata)")
    f.set_defaults(func=cmd_export_foxglove)

    p = subparsers.add_parser("animate", help="render a recorded run as a GIF or MP4",
                              description="Top view (world, path, footprint, the planner's "
                              "mind), speed and charge over time; time, speed and charge in "
                              "the title. MP4 needs ffmpeg.")
    p.add_argument("src", metavar="FILE.mcap")
    p.add_argument("out", metavar="OUT.gif|OUT.mp4")
    p.add_argument("--fps", type=float, default=10.0, help="frames per second (default 10)")
    p.add_argument("--speed", type=float, default=4.0,
                   help="sim seconds per video second (default 4)")
    p.add_argument("--world", help="world to draw (default: the recording's metadata)")
    p.add_argument("--dpi", type=int, default=80, help="resolution (default 80)")
    p.set_defaults(func=cmd_animate)


def cmd_view(args: argparse.Namespace) -> int:
    from common.transport import setup_logging
    from nodes.viewer.__main__ import serve

    if args.layout:
        from pathlib import Path

        from nodes.viewer.layout import layout_json

        Path(args.layout).write_text(layout_json())
        print(f"wrote {args.layout}")
        return 0
    return serve(args, setup_logging("viewer", args.log_level))


def cmd_export_foxglove(args: argparse.Namespace) -> int:
    from papf.recording.foxglove_export import export_foxglove

    stats = export_foxglove(args.src, args.dst, args.world)
    for note in stats.notes:
        print(f"papf export: {note}", file=sys.stderr)
    print(f"{args.dst}: {stats.written} Foxglove messages from {stats.read} recorded "
          f"({stats.skipped} skipped), world {stats.world or 'none'}")
    return 0


def cmd_animate(args: argparse.Namespace) -> int:
    from papf.animate import animate

    n = animate(args.src, args.out, args.fps, args.speed, args.world, args.dpi)
    print(f"{args.out}: {n} frames at {args.fps:g} fps ({args.speed:g}x)")
    return 0


def replay_with_view(args: argparse.Namespace, replay_fn) -> int:
    """``papf replay FILE --view PORT``: start the viewer (and a router if none is reachable
    on the default endpoint) next to the replay; keep serving after it until Ctrl-C."""
    import zenoh

    from common.transport import DEFAULT_ENDPOINT, StopRequested, config_from_args, wait_alive
    from papf.recording.reader import Recording
    from papf.recording.replay import recorded_namespace
    from papf.supervisor import Supervisor, port_in_use, wait_port
    from schemas import Keys

    with Recording(args.file) as rec:
        meta, recorded_ns = rec.run_metadata, recorded_namespace(rec)
    ns = args.namespace or recorded_ns or "rosbot"
    own_router = (args.mode == "client" and not args.connect and not args.zenoh_config
                  and not port_in_use(7447))
    stop = StopRequested()
    with Supervisor(show=lambda name, line: "ERROR" in line or "Foxglove" in line,
                    last=("router",)) as sup:
        if own_router:
            sup.start("router", [sys.executable, "-m", "papf.router", "--listen",
                                 DEFAULT_ENDPOINT])
            wait_port(7447, 15.0, abort=lambda: bool(sup.dead()))
        z = [a for ep in args.connect for a in ("--connect", ep)] + ["--namespace", ns,
                                                                      "--mode", args.mode]
        z += ["--zenoh-config", args.zenoh_config] if args.zenoh_config else []
        sup.start("viewer", [sys.executable, "-m", "nodes.viewer", *z,
                             *viewer_argv(args.view, meta.get("world"), "refuse")])
        with zenoh.open(config_from_args(args)) as session:
            if wait_alive(session, Keys(ns), ["viewer"], 30.0, abort=lambda: bool(sup.dead())):
                print(f"papf replay: the viewer did not start: {sup.death_reason()}",
                      file=sys.stderr)
                return 2
        code = replay_fn(args, stop)
        if code == 0:
            print(f"papf replay: done; the view stays on ws://127.0.0.1:{args.view} until "
                  "Ctrl-C", file=sys.stderr)
            while not stop and not sup.dead():
                stop.event.wait(0.2)
        return 130 if stop else code
