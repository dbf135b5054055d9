"""Every port the stack listens on inside one range: ``--port-range LO-HI`` (docs/robot.md,
"Ports and firewalls").

On a lab network with a firewall a user keeps the stack inside the ports it lets through.
The stack listens on: the router's port (``--port``, default 7447), and in peer mode
(``papf run``'s default, the ``sim`` profile) one port per node for its direct links to the
other nodes. Without a range those are picked by the OS; with one, every port the launcher
picks — the router's when 7447 is taken or outside the range, each peer node's, each run's of
an experiment — is a free port of the range. Client mode (``--zenoh-mode client``) needs
the router's port alone.

The range travels in the environment (:data:`ENV`), so it holds for every process and sweep
worker the command starts; ``--port-range`` on ``run``, ``launch`` and ``experiment`` and
``make demo PORT_RANGE=…`` set it.
"""

from __future__ import annotations

import os
import random
import socket
from dataclasses import dataclass

from common.errors import ConfigError

ENV = "PAPF_PORT_RANGE"
PORT_ENV = "PAPF_PORT"    # an experiment's --port: every run's router on it, one run at a time
LOWEST = 1024            # below: ports only root may listen on
_RANDOM = random.Random()


@dataclass(frozen=True)
class PortRange:
    lo: int
    hi: int

    def __contains__(self, port: object) -> bool:
        return isinstance(port, int) and self.lo <= port <= self.hi

    @property
    def size(self) -> int:
        return self.hi - self.lo + 1

    def __str__(self) -> str:
        return f"{self.lo}-{self.hi}"


def parse(text: str, what: str = "--port-range") -> PortRange:
    """``"7447-7460"`` as a :class:`PortRange`; ConfigError (one line, exit 2) otherwise."""
    lo, sep, hi = str(text).strip().partition("-")
    try:
        rng = PortRange(int(lo), int(hi))
    except ValueError:
        rng = None
    if not sep or rng is None or not (LOWEST <= rng.lo <= rng.hi <= 65535):
        raise ConfigError(f"{what} {text!r}: give LO-HI, two ports with {LOWEST} <= LO <= HI "
                          "<= 65535 (e.g. 7447-7460)")
    return rng


def current() -> PortRange | None:
    """The range of this process (:data:`ENV`), or None: the OS picks."""
    text = os.environ.get(ENV, "").strip()
    return parse(text, f"${ENV}") if text else None


def use(rng: PortRange | None, port: int | None = None) -> None:
    """Make ``rng`` this process's range (and its children's): ``--port-range``; ``port``:
    an experiment's ``--port``, the router port of each of its runs."""
    if rng is not None:
        os.environ[ENV] = str(rng)
    if port is not None:
        os.environ[PORT_ENV] = str(port)


def fixed_port() -> int | None:
    """An experiment's ``--port`` (:data:`PORT_ENV`), or None."""
    text = os.environ.get(PORT_ENV, "").strip()
    if not text:
        return None
    if not text.isdigit() or not 1 <= int(text) <= 65535:
        raise ConfigError(f"${PORT_ENV} {text!r}: give a port, 1-65535")
    return int(text)


def free_in_range(rng: PortRange, taken: set[int] | frozenset[int] = frozenset(),
                  lowest: bool = False) -> int:
    """A port of ``rng`` that nothing listens on and is not in ``taken``: the lowest one
    (``lowest``: a stack's router, where a user looks first), else tried in random order (the
    runs of an experiment picking at once rarely meet); ConfigError when none is left."""
    ports = list(range(rng.lo, rng.hi + 1))
    if not lowest:
        _RANDOM.shuffle(ports)
    for port in ports:
        if port in taken:
            continue
        with socket.socket() as s:
            try:
                s.bind(("127.0.0.1", port))
            except OSError:
                continue
        return port
    raise ConfigError(f"--port-range {rng}: no free port left ({rng.size} ports, "
                      f"{len(taken)} taken by this stack, the others in use): widen the range, "
                      "or --zenoh-mode client (the nodes then listen on no port)")


def node_listen_port(taken: set[int]) -> int:
    """The port a peer node listens on: 0 (the OS picks) without a range, else a free one of
    the range, added to ``taken``."""
    rng = current()
    if rng is None:
        return 0
    port = free_in_range(rng, taken)
    taken.add(port)
    return port


def check_port(port: int | None, what: str = "--port") -> None:
    """An explicit port outside the range is a contradiction: ConfigError."""
    rng = current()
    if port is not None and rng is not None and port not in rng:
        raise ConfigError(f"{what} {port} is outside --port-range {rng}; give a port inside it, "
                          "or leave --port out (the range's first free port is taken)")
