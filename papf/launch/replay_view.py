"""``papf replay FILE --view PORT``: the replay with a Foxglove viewer beside it.

Starts the viewer node (and the embedded router when the replay would go to the default
endpoint and nothing listens there), waits for it, replays, and keeps serving until Ctrl-C.
Goals from the viewer are refused: a recording does not change.
"""

from __future__ import annotations

import argparse
import sys


def replay_with_view(args: argparse.Namespace, replay_fn) -> int:
    """``papf replay FILE --view PORT``: start the viewer (and a router if none is reachable
    on the default endpoint) next to the replay; keep serving after it until Ctrl-C."""
    import zenoh

    from common.transport import DEFAULT_ENDPOINT, StopRequested, config_from_args, wait_alive
    from papf.launch.preflight import view_port
    from papf.launch.supervisor import Supervisor, port_in_use, wait_port
    from papf.recording.replay import recorded_namespace
    from papf.recording.rosbag import SOURCE, TopicMap, open_run
    from schemas import Keys

    view_port(args.view)   # a busy port: exit 2 before the router and viewer start
    with open_run(args.file, TopicMap.parse(getattr(args, "topics", None))) as rec:
        meta, recorded_ns = rec.run_metadata, recorded_namespace(rec)
    ns = args.namespace or recorded_ns or "rosbot"
    own_router = (args.mode == "client" and not args.connect and not args.zenoh_config
                  and not port_in_use(7447))
    stop = StopRequested()
    with Supervisor(show=lambda name, line: "ERROR" in line or "Foxglove" in line,
                    last=("router",)) as sup:
        if own_router:
            sup.start("router", [sys.executable, "-m", "papf.launch.router", "--listen",
                                 DEFAULT_ENDPOINT])
            wait_port(7447, 15.0, abort=lambda: bool(sup.dead()))
        z = [a for ep in args.connect for a in ("--connect", ep)] + ["--namespace", ns,
                                                                      "--mode", args.mode]
        z += ["--zenoh-config", args.zenoh_config] if args.zenoh_config else []
        world = (["--world", meta["world"]] if meta.get("world") and meta.get("source") != SOURCE
                 else [])
        sup.start("viewer", [sys.executable, "-m", "nodes.viewer", *z, "--port", str(args.view),
                             "--goals", "refuse", *world])
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
                stop.wait(0.2)
        return 130 if stop else code
