"""The embedded Zenoh router (docs/architecture.md "Transport"): ``python -m papf.launch.router``.

Runs a Zenoh session in ``router`` mode listening on ``tcp/127.0.0.1:7447`` (by
default) until SIGINT/SIGTERM, so no external ``zenohd`` is needed. ``--join ENDPOINT``
connects it to another host's router: a fleet's robots, each with its own router, form
one Zenoh network (``papf launch robot --namespace r2 --join tcp/<r1>:7447``).
"""

from __future__ import annotations

import zenoh

from common.cliparse import ArgumentParser
from common.transport import (
    DEFAULT_ENDPOINT,
    STOP_BOUND_S,
    StopRequested,
    setup_logging,
    watch_parent,
    zenoh_config,
)


def main(listen: list[str], config_file: str | None = None, join: list[str] | None = None) -> None:
    log = setup_logging("router")
    stop = StopRequested(bound_s=STOP_BOUND_S)   # started by a launcher: a bounded stop,
    watch_parent(stop)                           # and none after the launcher is gone
    # without a config file (no multicast, no connect): no one to scout for, no 0.5 s delay;
    # ``join``: the routers of a fleet's other hosts, so they make one network
    conf = zenoh_config("router", connect=join or (), listen=listen, config_file=config_file,
                        scout_delay_ms=None if config_file else 0)
    with zenoh.open(conf) as session:
        log.info("Zenoh router %s listening on %s", session.zid(), ", ".join(listen))
        while not stop.wait(0.2):
            pass
    log.info("router stopped")


if __name__ == "__main__":
    parser = ArgumentParser(prog="python -m papf.launch.router", description=__doc__.splitlines()[0])
    parser.add_argument("--listen", action="append", default=[], metavar="ENDPOINT",
                        help=f"endpoint to listen on (default {DEFAULT_ENDPOINT})")
    parser.add_argument("--zenoh-config", metavar="FILE", help="Zenoh JSON5 config (TLS, ACL)")
    parser.add_argument("--join", action="append", default=[], metavar="ENDPOINT",
                        help="another router to connect to (a fleet's hosts in one network)")
    a = parser.parse_args()
    main(a.listen or [DEFAULT_ENDPOINT], a.zenoh_config, a.join)
