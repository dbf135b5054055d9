"""One launch per namespace: a second ``papf launch`` whose nodes a running one already has
is refused — exit 2, one line — before it starts anything.

Two launches in one namespace would share every key: two planners commanding one robot,
two drivers answering one ``cmd_vel``, two meters on one ``battery``. Two checks:

- **On this host** (:class:`Claim`): the launcher holds an exclusive ``flock`` on a file per
  node it starts, ``<runtime dir>/papf-<uid>/<namespace>.<node>.lock`` (beside the run keys
  of :mod:`common.runauth`). The kernel drops the lock when the launcher dies, however it
  dies, so a crashed launch never blocks the next one. ``papf launch robot`` and ``papf
  launch laptop`` on one host start different nodes and do not clash.
- **On the network it joins** (:func:`check_network`): a launch whose nodes connect to
  another host's router (``laptop``, ``hil-laptop``, a router with ``--join``) first asks
  that network which nodes of the namespace are alive (their liveliness tokens).
"""

from __future__ import annotations

import fcntl
import os
import re
from collections.abc import Iterable

import zenoh

from common import runauth
from common.errors import ConfigError
from common.reach import session_error
from common.transport import alive_nodes, connect_endpoints
from schemas import Keys

ASK_S = 1.0   # [s] how long the network's liveliness replies are awaited


def lock_path(namespace: str, node: str):
    """The lock file of ``node`` in ``namespace`` for this user on this host."""
    safe = re.sub(r"[^A-Za-z0-9_.-]", "_", namespace)
    return runauth.key_file(namespace).parent / f"{safe}.{node}.lock"


class Claim:
    """``with Claim("rosbot", "robot", ["base_driver", "lidar_sim"]):`` — the nodes are this
    launch's for as long as the block runs; ConfigError at entry if another launch of this
    user on this host holds one of them."""

    def __init__(self, namespace: str, profile: str, nodes: Iterable[str]):
        self.namespace, self.profile, self.nodes = namespace, profile, list(nodes)
        self._fds: list[int] = []

    def __enter__(self) -> Claim:
        taken: dict[str, str] = {}
        for node in self.nodes:
            path = lock_path(self.namespace, node)
            path.parent.mkdir(mode=0o700, exist_ok=True)
            fd = os.open(path, os.O_RDWR | os.O_CREAT | getattr(os, "O_NOFOLLOW", 0), 0o600)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                taken[node] = os.pread(fd, 200, 0).decode(errors="replace").strip()
                os.close(fd)
                continue
            os.ftruncate(fd, 0)
            os.pwrite(fd, f"process {os.getpid()}, papf launch {self.profile}".encode(), 0)
            self._fds.append(fd)
        if taken:
            self.__exit__()
            holders = sorted(set(taken.values()))
            raise ConfigError(f"namespace {self.namespace!r} is in use on this host: "
                              f"{', '.join(sorted(taken))} already run by {'; '.join(holders)}; "
                              "stop that launch, or give another --namespace")
        return self

    def __exit__(self, *exc) -> None:
        for fd in self._fds:
            os.close(fd)      # closing the last descriptor releases the lock
        self._fds = []


def check_network(conf: zenoh.Config, keys: Keys, nodes: Iterable[str], config_file: str | None,
                  ask_s: float = ASK_S) -> None:
    """ConfigError if a node named in ``nodes`` is alive in ``keys``' namespace on the network
    ``conf`` connects to (or that network cannot be reached: :mod:`common.reach`)."""
    endpoints = connect_endpoints(conf)
    try:
        session = zenoh.open(conf)
    except zenoh.ZError as exc:
        raise session_error(exc, endpoints, config_file, ", ".join(endpoints)) from None
    with session:
        taken = sorted(alive_nodes(session, keys, ask_s) & set(nodes))
    if taken:
        raise ConfigError(f"namespace {keys.ns!r} is in use on the network at "
                          f"{', '.join(endpoints)}: {', '.join(taken)} already alive there "
                          "(another papf launch?); stop that launch, or give another --namespace")
