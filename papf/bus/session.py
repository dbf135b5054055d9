"""The Zenoh session of a bus tool, from the nodes' options; a router that is not there is a
one-line error (exit 2), not a traceback."""

from __future__ import annotations

import argparse

import zenoh

from common.errors import ConfigError
from common.transport import DEFAULT_ENDPOINT, config_from_args


def open_session(args: argparse.Namespace) -> zenoh.Session:
    """``zenoh.open`` with ``--connect``/``--mode``/``--zenoh-config``; ConfigError if unreachable."""
    conf = config_from_args(args)
    try:
        return zenoh.open(conf)
    except Exception as exc:  # zenoh raises ZError with the orchestrator's message
        where = ", ".join(args.connect) or (args.zenoh_config and f"the endpoints of "
                                            f"{args.zenoh_config}") or DEFAULT_ENDPOINT
        reason = str(exc).split(" at /")[0].split("\n")[0]
        if any(ep.startswith(("tls/", "quic/")) for ep in args.connect) and not args.zenoh_config:
            raise ConfigError(f"cannot open a session with {where} ({reason}): a TLS router "
                              "authenticates its clients, and this command has no certificate "
                              "or credentials; give --zenoh-config with this host's config "
                              "(papf make-certs writes laptop.json5, docs/robot.md)") from None
        raise ConfigError(f"cannot reach the bus at {where} ({reason}); is a stack running "
                          "(papf run, papf launch, python -m papf.launch.router)? Else give "
                          "--connect ENDPOINT") from None
