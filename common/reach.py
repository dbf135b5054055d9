"""Why a Zenoh session did not open, in one line (exit 2), instead of Zenoh's "Unable to connect".

Zenoh says the same thing whether nothing listens at the endpoint or a router there
refused us (a TLS router without our certificate, a wrong password): :func:`session_error`
tells the two apart by trying a plain TCP connection to the endpoint's port. A port that
accepts is a router that is up and refused the session — an authentication failure —
and the message says which credentials were missing or not accepted; a port that does not
is no router at all.
"""

from __future__ import annotations

import re
import socket
from collections.abc import Sequence

from common.errors import ConfigError

PROBE_S = 1.0   # [s] longest wait for a TCP connection to the endpoint's port
_HOST_PORT = re.compile(r"^(?P<proto>tcp|tls|ws)/(?P<host>\[[0-9a-fA-F:.]+\]|[^/:\[\]#]+):"
                        r"(?P<port>\d+)(#.*)?$")


def accepts(endpoint: str, timeout_s: float = PROBE_S) -> bool:
    """True when the TCP port of ``endpoint`` (``tcp|tls|ws/HOST:PORT``) accepts a connection
    (False for UDP, QUIC, unix sockets and anything that does not)."""
    m = _HOST_PORT.match(endpoint)
    if m is None:
        return False
    host = "127.0.0.1" if m.group("host") in ("0.0.0.0", "[::]") else m.group("host").strip("[]")
    try:
        with socket.create_connection((host, int(m.group("port"))), timeout=timeout_s):
            return True
    except OSError:
        return False


def session_error(exc: Exception, endpoints: Sequence[str], config_file: str | None,
                  where: str) -> ConfigError:
    """The one-line error for a session that did not open (``exc``: Zenoh's) to ``endpoints``
    (``where``: how to name them), with ``config_file`` the ``--zenoh-config`` given or None."""
    reason = str(exc).split(" at /")[0].split("\n")[0].strip()
    up = [ep for ep in endpoints if accepts(ep)]
    if not up:
        tls = "" if config_file or not any(ep.startswith(("tls/", "quic/")) for ep in endpoints) \
            else ("; once it is, a TLS router authenticates its clients: give --zenoh-config "
                  "with this host's config (papf make-certs writes laptop.json5)")
        return ConfigError(f"cannot reach the bus at {where} ({reason}): nothing accepts a "
                           "connection there; is a stack running (papf run, papf launch, python "
                           f"-m papf.launch.router)? Else give --connect ENDPOINT{tls}")
    secure = any(ep.startswith(("tls/", "quic/")) for ep in up)
    if config_file is None:
        need = ("a TLS router authenticates its clients (certificate, user and password) and "
                "this command has none" if secure else
                "the router there asks for credentials (user and password) this command does "
                "not have, or it is not a Zenoh router")
        return ConfigError(f"authentication failed at {', '.join(up)}: the router is up and "
                           f"refused this session; {need}. Give --zenoh-config with this host's "
                           "config (papf make-certs writes laptop.json5; docs/robot.md)")
    return ConfigError(f"authentication failed at {', '.join(up)}: the router is up and refused "
                       f"the credentials of {config_file} (its certificate, CA or user/password "
                       "do not match the router's bundle; papf make-certs, docs/robot.md)")
