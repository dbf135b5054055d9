"""Subcommands contributed by feature packages: each module exposes ``register(subparsers)``.

Listed by module path and imported when the parser is built, so `papf --help` shows
them all while `papf run` does not pay for importing matplotlib or rosbags.
"""

from __future__ import annotations

import importlib

MODULES = (
    "papf.recording.cli",   # record, replay, recover, info
    "papf.bench_cli",       # bench
    "papf.plan_cli",        # plan, experiment paper-tests, experiment random
    "papf.report_cli",      # report, experiment energy
    "papf.robot_cli",       # launch, rosbot-emulator, make-certs
    "papf.viewer_cli",      # view, export foxglove, animate
)


def registrars() -> list:
    return [importlib.import_module(m).register for m in MODULES]
