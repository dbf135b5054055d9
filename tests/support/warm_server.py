"""The tests' warm ``papf`` (:mod:`tests.support.warm`): :mod:`papf.launch.forkserver`'s
server, after loading what most ``papf`` commands import (:data:`PRELOAD`)."""

from __future__ import annotations

import importlib

from papf.cli import COMMANDS
from papf.launch import forkserver

# the CLI and every command's module (their own imports are mostly made when they run), the
# launcher, and what the commands that draw or read recordings load: none starts a thread
PRELOAD = (*(f"papf.cli.{module}" for _, module in COMMANDS), "papf.launch.run",
           "papf.launch.supervisor", "matplotlib", "matplotlib.pyplot", "mcap.reader",
           "papf.recording.reader")


if __name__ == "__main__":
    for name in PRELOAD:
        importlib.import_module(name)
    forkserver.main()
