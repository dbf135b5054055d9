"""The tests' warm ``papf`` (:mod:`tests.support.warm`): :mod:`papf.launch.forkserver`'s
server, after loading what most ``papf`` commands import (:data:`PRELOAD`)."""

from __future__ import annotations

import importlib
import os
import runpy
import socket
import sys

from papf.launch import forkserver

# the CLI and every command's module (their own imports are mostly made when they run), the
# launcher, and what the commands that draw or read recordings load: none starts a thread
PRELOAD = ("papf.cli", *(f"papf.cli.{module}" for _, module in __import__("papf.cli").cli.COMMANDS),
           "papf.launch.run", "papf.launch.supervisor", "matplotlib", "matplotlib.pyplot",
           "mcap.reader", "papf.recording.reader")


def main() -> None:
    for name in PRELOAD:
        importlib.import_module(name)
    sock = socket.socket(fileno=int(sys.argv[-2]))
    request = forkserver.serve(sock)
    forkserver.become(request)
    sys.path[0] = os.getcwd()   # as `python -m` puts it: the caller's working directory
    runpy.run_module(request["argv"][0], run_name="__main__", alter_sys=True)


if __name__ == "__main__":
    main()
