"""The robot commands of `papf`: ``launch``, ``rosbot-emulator``, ``make-certs``.

``register(subparsers)`` is listed in :data:`papf.commands.MODULES`.
"""

from __future__ import annotations

import argparse
import json
import sys

from papf.viewer_cli import add_view_flag


def register(sub) -> None:
    _add_launch(sub)
    p = sub.add_parser("rosbot-emulator", help="emulate the ROSbot behind zenoh-bridge-ros2dds",
                       description="Subscribe CDR cmd_vel, drive a unicycle with the ROSbot's "
                                   "limits, publish CDR odometry/filtered, battery (and scan "
                                   "with --world), as the real robot does through the bridge.")
    add_emulator_arguments(p)
    p.set_defaults(func=_cmd_emulator)
    p = sub.add_parser("make-certs", help="test CA, certificates and secure Zenoh configs",
                       description="Write a test CA, robot/laptop certificates (openssl), a "
                                   "password dictionary and the Zenoh configs of the secure "
                                   "split (TLS + user/password + access control) into DIR.")
    p.add_argument("dir", help="output directory (created)")
    p.add_argument("--robot-host", action="append", default=[], required=True, metavar="HOST",
                   help="IP or DNS name the laptop uses for the robot (repeatable; first = "
                        "the laptop's connect endpoint)")
    p.add_argument("--namespace", default="rosbot", help="our key namespace (rosbot)")
    p.add_argument("--bridge-namespace", default="", help="zenoh-bridge-ros2dds namespace")
    p.set_defaults(func=_cmd_make_certs)


def add_emulator_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of `papf rosbot-emulator` (here, so that building the CLI imports no rosbags)."""
    from common.transport import add_zenoh_args

    parser.add_argument("--bridge-namespace", default="", metavar="NS",
                        help="bridge namespace of the emulated topics (default: none)")
    parser.add_argument("--world", help="world the robot stands in: scan it (start pose too)")
    parser.add_argument("--no-scan", action="store_true", help="no LaserScan even with --world")
    parser.add_argument("--scan-beams", type=int, default=720, help="LaserScan readings (720)")
    parser.add_argument("--seed", type=int, default=0, help="scan noise seed (0)")
    parser.add_argument("--rate", type=float, default=50.0, help="odometry rate [Hz] (50)")
    parser.add_argument("--cmd-timeout", type=float, default=0.5, metavar="S",
                        help="controller cmd_vel_timeout [s] (0.5; 0 = never)")
    parser.add_argument("--battery-voltage", type=float, default=12.0, metavar="V",
                        help="pack voltage reported on battery (12.0)")
    parser.add_argument("--trace", metavar="FILE", help="append a JSON line per command received")
    parser.add_argument("--log-level", default="INFO")
    add_zenoh_args(parser)


def _add_launch(sub) -> None:
    p = sub.add_parser("launch", help="start this host's part of the stack from a profile",
                       description="Profiles: sim, robot, laptop, hil-robot, hil-laptop (or a "
                                   ".toml path). Exit code as `papf run` for profiles that drive "
                                   "a run; 0 after Ctrl-C for the others.")
    p.add_argument("profile", help="packaged profile name or .toml path")
    p.add_argument("--connect", action="append", default=[], metavar="ENDPOINT",
                   help="where this host's nodes connect, e.g. tcp/192.168.1.10:7447")
    p.add_argument("--listen", action="append", default=[], metavar="ENDPOINT",
                   help="the router's endpoints (profiles with a router)")
    p.add_argument("--namespace", default="rosbot", help="robot key namespace (rosbot)")
    p.add_argument("--bridge-namespace", help="zenoh-bridge-ros2dds namespace (default none)")
    p.add_argument("--zenoh-config", metavar="FILE", help="Zenoh config of the nodes (secure split)")
    p.add_argument("--router-config", metavar="FILE", help="Zenoh config of the router")
    p.add_argument("--world", help="world (runs; robot side: its start pose)")
    p.add_argument("--planner", help="apf | papf | arapf | wang")
    p.add_argument("--seed", type=int)
    p.add_argument("--record", metavar="F.mcap", help="record every message here")
    p.add_argument("--energy-model", choices=("motor", "paper"))
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="planner parameter, repeatable")
    p.add_argument("--timeout", type=float, default=300.0, metavar="S", help="run-time limit (300)")
    p.add_argument("--stall-timeout", type=float, default=20.0, metavar="S",
                   help="fail a run after S wall seconds without the driver's clock (20)")
    p.add_argument("--startup-timeout", type=float, default=60.0, metavar="S")
    p.add_argument("--json", action="store_true", help="print the run summary as one JSON object")
    p.add_argument("--dry-run", action="store_true", help="print the commands, start nothing")
    p.add_argument("--verbose", "-v", action="store_true", help="show every node's log lines")
    add_view_flag(p)
    p.set_defaults(func=_cmd_launch)


def _cmd_launch(args) -> int:
    from papf.launch import LaunchOptions, launch

    values = {"world": args.world, "planner": args.planner, "seed": args.seed,
              "record": args.record, "energy_model": args.energy_model,
              "bridge_namespace": args.bridge_namespace}
    opt = LaunchOptions(args.profile, args.connect, args.listen, args.namespace, args.zenoh_config,
                        args.router_config, {k: v for k, v in values.items() if v is not None},
                        [x for kv in args.set for x in ("--set", kv)], args.timeout,
                        args.startup_timeout, args.stall_timeout, args.verbose, args.dry_run,
                        view=args.view)
    result = launch(opt)
    if result is None:
        return 0
    if args.json:
        print(json.dumps(result.to_json()), flush=True)
    else:
        print(f"papf launch {args.profile}: {result.outcome} after {result.sim_time_s:.2f} s "
              f"({result.path_length_m:.2f} m, {result.charge_mAh:.2f} mAh) {result.reason}")
    return 130 if result.reason == "interrupted" else result.exit_code


def _cmd_emulator(args) -> int:
    from papf.emulator import run

    return run(args)


def _cmd_make_certs(args) -> int:
    from nodes.base_driver.rosbot import BridgeTopics
    from papf.security import write_bundle

    b = write_bundle(args.dir, args.robot_host, args.namespace, BridgeTopics(args.bridge_namespace))
    print(f"wrote {b.dir}: ca.pem, robot.pem/.key, laptop.pem/.key, credentials.txt, "
          "router.json5, robot.json5, laptop.json5, observer.json5\n"
          f"robot:  papf launch robot --router-config {b.router} --zenoh-config {b.robot} "
          "--listen tcp/127.0.0.1:7447 --listen tls/0.0.0.0:7448\n"
          f"laptop: papf launch laptop --zenoh-config {b.laptop} --world W", file=sys.stderr)
    return 0


def main(argv: list[str] | None = None) -> int:
    """``python -m papf.robot_cli launch ...`` (the same as ``papf launch ...``)."""
    parser = argparse.ArgumentParser(prog="papf")
    register(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(argv)
    from common.errors import PapfError

    try:
        return args.func(args)
    except PapfError as exc:
        print(f"papf {args.command}: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
