"""The ``papf`` command. ``papf <command> --help`` for each command.

One module per subcommand (or family of subcommands), each exposing
``register(subparsers)``; :data:`COMMANDS` lists them in ``--help`` order. The handlers
import what they run when they run (the stack, pybullet, matplotlib, rosbags), so
building the parser — ``papf --help``, and ``papf run`` before its first process — loads
none of it. Nothing imports ``papf.cli``: it is the top of the house, and those imports
cannot hide a cycle (``tests/unit/test_layers.py`` checks).

Exit codes: 0 done / reached, 2 usage or configuration error (one line, no traceback),
3 stagnated, 4 collision, 5 timeout, 6 failed, 130 interrupted.
"""

from __future__ import annotations

import signal

# first (the `papf` script imports this module before anything else of ours): a SIGINT
# inherited as ignored from a script's `papf … &` is taken again at once, not after the
# imports below — one sent meanwhile would be discarded (papf/__main__.py says more)
signal.signal(signal.SIGINT, signal.default_int_handler)

import importlib  # noqa: E402
import logging  # noqa: E402
import os  # noqa: E402
import sys  # noqa: E402

from common import __version__  # noqa: E402
from common.cliparse import ArgumentParser  # noqa: E402
from common.errors import PapfError  # noqa: E402
from common.text import install_log_filter, print_error  # noqa: E402

# (command, module of papf.cli that registers it), in ``--help`` order. ``papf COMMAND``
# imports that one module only (``papf run`` starts its processes ~0.2 s sooner than if
# every command's imports came first); ``papf --help`` or a misspelt command, all of them.
COMMANDS = (("run", "run"), ("worlds", "worlds"), ("launch", "launch"), ("topic", "topic"),
            ("node", "node"), ("goal", "goal"), ("param", "param"), ("teleop", "teleop"),
            ("plan", "plan"), ("experiment", "experiment"), ("report", "report"),
            ("record", "record"), ("replay", "replay"), ("recover", "recover"), ("info", "info"),
            ("view", "view"), ("export", "export"), ("animate", "animate"), ("bench", "bench"),
            ("rosbot-emulator", "emulator"), ("link", "link"), ("make-certs", "certs"), ("new", "new"))


def build_parser(command: str | None = None) -> ArgumentParser:
    """The ``papf`` parser: the command modules of :data:`COMMANDS` register their
    subcommands — only ``command``'s when it names one, else every one. A usage error is
    one line, whole, with did-you-mean from the parser's own options and choices
    (:class:`common.cliparse.ArgumentParser`), and exit 2."""
    parser = ArgumentParser(prog="papf", description=__doc__.split("\n\n")[0])
    parser.add_argument("--version", action="version", version=f"papf-stack {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    wanted = [m for name, m in COMMANDS if name == command] or [m for _, m in COMMANDS]
    for module in wanted:
        importlib.import_module(f"papf.cli.{module}").register(sub)
    return parser


def _sigterm_as_interrupt(*_) -> None:
    raise KeyboardInterrupt  # same clean stop as Ctrl-C: every child process is stopped


SUBCOMMAND_DEST = {"topic": "topic_command", "node": "node_command", "experiment": "experiment",
                   "export": "format", "new": "kind"}   # the commands that have subcommands


def _prog(args) -> str:
    """``papf COMMAND [SUBCOMMAND]`` as the user typed it (``papf topic pub``)."""
    sub = getattr(args, SUBCOMMAND_DEST.get(args.command, ""), None)
    return f"papf {args.command}" + (f" {sub}" if isinstance(sub, str) else "")


def main(argv: list[str] | None = None) -> int:
    """``papf``: parse ``argv``, run the command; its exit code (2 on a user's mistake)."""
    logging.basicConfig(level=logging.INFO, format="%(levelname)s %(name)s: %(message)s")
    install_log_filter()   # a world's or a peer's text in a log line: shown, never run
    signal.signal(signal.SIGTERM, _sigterm_as_interrupt)
    # a command started in the background by a script inherits SIGINT ignored (the shell's
    # rule for `cmd &`); `kill -INT` must still stop every child process cleanly
    signal.signal(signal.SIGINT, signal.default_int_handler)
    argv = sys.argv[1:] if argv is None else argv
    args = build_parser(argv[0] if argv else None).parse_args(argv)
    try:
        return args.func(args)
    except PapfError as exc:
        print_error(_prog(args), str(exc))   # whole: the fix hint is at its end
        return 2
    except KeyboardInterrupt:
        print(f"papf {args.command}: interrupted; every process was stopped", file=sys.stderr)
        return 130
    except BrokenPipeError:   # `papf … | head`: the reader has what it wanted
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0


def entry() -> None:
    """The ``papf`` console script and ``python -m papf``: :func:`main`, then the exit.

    After ``papf run`` — every process it started stopped and their last output lines printed
    (:meth:`papf.launch.supervisor.Supervisor.stop`), its Zenoh session closed, the result printed —
    the interpreter's teardown of numpy, Zenoh and rich is skipped
    (:func:`common.transport.exit_fast`: logs and streams flushed, then ``os._exit``).
    """
    code = main()
    if sys.argv[1:2] == ["run"]:
        from common.transport import exit_fast  # loaded by the run already: no import cost

        exit_fast(code)
    sys.exit(code)
