"""The `papf` command (DESIGN.md §10). `papf <command> --help` for each command."""

from __future__ import annotations

import argparse
import json
import logging
import signal
import sys

from common.errors import PapfError
from papf.viewer_cli import add_view_flag

log = logging.getLogger("papf")


def _add_run(sub) -> None:
    p = sub.add_parser("run", help="run the whole simulated stack once, to an outcome",
                       description="Start router, lidar_sim, base_driver (sim), planner and "
                                   "energy_meter as processes; drive to the world's goal; print a "
                                   "summary. Exit code: 0 reached, 3 stagnated, 4 collision, "
                                   "5 timeout, 6 failed, 2 usage error.")
    p.add_argument("--world", required=True, help="packaged world name or path to a .toml")
    p.add_argument("--planner", default="apf", help="apf | papf | arapf | wang (default apf)")
    p.add_argument("--seed", type=int, default=0, help="seed of all noise (default 0)")
    p.add_argument("--record", metavar="F.mcap", help="record every message to this MCAP file")
    p.add_argument("--timeout", type=float, default=300.0, metavar="S",
                   help="sim-time limit in seconds (default 300)")
    p.add_argument("--realtime", action="store_true", help="pace sim time to the wall clock")
    p.add_argument("--json", action="store_true", help="print one JSON object, nothing else")
    p.add_argument("--port", type=int, help="embedded router port (default 7447, or a free one)")
    p.add_argument("--namespace", default="rosbot", help="robot key namespace")
    p.add_argument("--zenoh-mode", choices=("client", "peer"), default="client",
                   help="nodes' Zenoh mode: client (all through the router, default) or peer "
                        "(direct loopback links too; a few %% faster)")
    p.add_argument("--energy-model", choices=("motor", "paper"), default="motor")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="planner parameter override, repeatable (e.g. --set v_max=0.3)")
    p.add_argument("--params", metavar="FILE.toml", help="planner parameters from a TOML file")
    p.add_argument("--continue-on-collision", action="store_true",
                   help="count collisions but keep driving (default: a collision ends the run)")
    p.add_argument("--verbose", "-v", action="store_true", help="show every node's log lines")
    add_view_flag(p)
    p.set_defaults(func=_cmd_run)


def _cmd_run(args) -> int:
    from papf.runner import RunConfig, run

    planner_args = [x for kv in args.set for x in ("--set", kv)]
    if args.params:
        planner_args += ["--params", args.params]
    cfg = RunConfig(world=args.world, planner=args.planner, seed=args.seed,
                    timeout_s=args.timeout, realtime=args.realtime, record=args.record,
                    port=args.port, namespace=args.namespace, planner_args=planner_args,
                    energy_model=args.energy_model,
                    stop_on_collision=not args.continue_on_collision, verbose=args.verbose,
                    zenoh_mode=args.zenoh_mode, view=args.view,
                    progress=None if not args.json else False)
    result = run(cfg)
    if args.json:
        print(json.dumps(result.to_json()))
    else:
        _print_summary(result)
    return result.exit_code


def _print_summary(result) -> None:
    from rich.console import Console
    from rich.table import Table

    colour = "green" if result.outcome == "reached" else "red"
    t = Table(title=f"papf run: [{colour}]{result.outcome}[/]", show_header=False)
    rows = [("world", result.world), ("planner", result.planner), ("seed", str(result.seed)),
            ("duration", f"{result.duration_s:.2f} s"),
            ("path length", f"{result.path_length_m:.2f} m"),
            ("charge", f"{result.charge_mAh:.2f} mAh"), ("energy", f"{result.energy_J:.1f} J"),
            ("collisions", str(result.collisions)), ("sim time", f"{result.sim_time_s:.2f} s"),
            ("wall time", f"{result.wall_time_s:.2f} s  "
                          f"({result.sim_time_s / max(result.wall_time_s, 1e-9):.1f}x real time)")]
    if result.reason:
        rows.append(("reason", result.reason))
    for k, v in rows:
        t.add_row(k, v)
    Console().print(t)


def _add_worlds(sub) -> None:
    p = sub.add_parser("worlds", help="list the packaged worlds")
    p.set_defaults(func=_cmd_worlds)


def _cmd_worlds(args) -> int:
    from worlds import load_world, packaged_worlds

    for name in packaged_worlds():
        print(f"{name:24} {load_world(name).description.splitlines()[0][:90]}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="papf", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    _add_run(sub)
    _add_worlds(sub)
    for register in _optional_commands():
        register(sub)
    return parser


def _optional_commands():
    """Subcommands that live with their feature's package."""
    from papf.commands import registrars

    return registrars()


def _sigterm_as_interrupt(*_) -> None:
    raise KeyboardInterrupt  # same clean stop as Ctrl-C: every child process is stopped


def main(argv: list[str] | None = None) -> int:
    logging.basicConfig(level=logging.INFO, format="%(levelname)s %(name)s: %(message)s")
    signal.signal(signal.SIGTERM, _sigterm_as_interrupt)
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except PapfError as exc:
        print(f"papf {args.command}: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"papf {args.command}: interrupted; every process was stopped", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
