"""The real ROSbot's base driver: ``python -m nodes.base_driver --driver rosbot ...``.

``--driver rosbot`` drives the robot through ``zenoh-bridge-ros2dds`` or rmw_zenoh
(:mod:`nodes.base_driver.rosbot_node`: the command gate and its limits, the plan follower and
collision monitor of a slow link, the robot's odometry on the run's clock).
``--driver sim`` (the default, kept for scripts written before the simulator had a node of
its own) hands over to the world simulator: this process becomes ``python -m
nodes.world_sim`` with the same options (``execv``: the same process id, so a supervisor's
signals and a parent's death reach it), whose ``--help`` lists them.

Ports: :mod:`nodes.base_driver.ports` (``--help`` prints them).

Settings: ``--world`` (the world whose start is the robot's pose when a run starts),
``--odom-hz`` (50: the tick of odometry, wheels and clock), ``--watchdog`` (0.5 s), the
bridge's topics, the link driving's settings, the ROS 2 middleware, plus the Zenoh options.
``--seed``, ``--scan-hz``, ``--lockstep-timeout`` and ``--realtime`` are the simulator's:
taken and unused here (the robot is always real time), so one command line serves both.
Liveliness token: ``<ns>/alive/base_driver``.
"""

from __future__ import annotations

import argparse
import os
import sys

from common.cliparse import ArgumentParser
from common.drive import add_driver_args
from common.errors import PapfError
from common.ports import describe, plain
from common.transport import add_zenoh_args, exit_fast
from nodes.base_driver.ports import PORTS, VARIANTS

SIMULATOR = "nodes.world_sim"   # what --driver sim runs (another node: started, never imported)


def simulator_argv(argv: list[str]) -> list[str] | None:
    """The world simulator's command line when ``argv`` asks for ``--driver sim`` (explicitly,
    or by default unless for ``--help``: then this driver's help), else None."""
    pre = argparse.ArgumentParser(add_help=False, allow_abbrev=False)
    pre.add_argument("--driver", nargs="?", const="", default=None)
    pre.add_argument("-h", "--help", action="store_true")
    known, _ = pre.parse_known_args(argv)
    if known.driver not in (None, "sim") or (known.driver is None and known.help):
        return None   # the robot's driver, its help, or a mistake its parser names
    rest, skip = [], False
    for i, arg in enumerate(argv):
        if skip:
            skip = False
        elif arg == "--driver" and i + 1 < len(argv):
            skip = True
        elif not arg.startswith("--driver="):
            rest.append(arg)
    return [sys.executable, "-m", SIMULATOR, *rest]


def build_parser() -> argparse.ArgumentParser:
    parser = ArgumentParser(prog="python -m nodes.base_driver",
                            description=plain(__doc__.split("\n\n")[0]),
                            formatter_class=argparse.RawDescriptionHelpFormatter,
                            epilog=plain(__doc__.split("\n\n", 1)[1]) + "\n"
                            + describe(PORTS, VARIANTS))
    parser.add_argument("--driver", choices=("sim", "rosbot"), default="sim",
                        help="the real robot (rosbot), or the world simulator (sim, the default: "
                             "python -m nodes.world_sim)")
    add_driver_args(parser, simulator=False)
    add_zenoh_args(parser)
    return parser


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    simulator = simulator_argv(argv)
    if simulator is not None:
        if not {"-h", "--help"} & set(argv):   # a mistake named against this node's options
            build_parser().parse_args(argv)     # (--drivr: did you mean --driver?), exit 2
        sys.stdout.flush()
        os.execv(sys.executable, simulator)   # no return: this process is the simulator now
    from nodes.base_driver import rosbot_node  # imported only when asked: it pulls in rosbags

    parser = build_parser()
    rosbot_node.add_arguments(parser)
    args = parser.parse_args(argv)
    try:
        return rosbot_node.main(args) or 0
    except PapfError as exc:
        print(f"base_driver: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    exit_fast(main())   # the session is closed: skip the interpreter's slow teardown
