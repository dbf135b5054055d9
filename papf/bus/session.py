"""The Zenoh session of a bus tool, from the nodes' options; a router that is not there is a
one-line error (exit 2), not a traceback."""

from __future__ import annotations

import argparse

import zenoh

from common.reach import session_error
from common.transport import config_from_args, connect_endpoints


def open_session(args: argparse.Namespace) -> zenoh.Session:
    """``zenoh.open`` with ``--connect``/``--mode``/``--zenoh-config``; ConfigError if it does
    not open (no router there, or one that refused our credentials: :mod:`common.reach`)."""
    conf = config_from_args(args)
    try:
        return zenoh.open(conf)
    except Exception as exc:  # zenoh raises ZError with the orchestrator's message
        endpoints = connect_endpoints(conf)
        raise session_error(exc, endpoints, args.zenoh_config,
                            ", ".join(endpoints) or "the endpoints of --zenoh-config") from None
