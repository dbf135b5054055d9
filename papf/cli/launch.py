"""``papf launch PROFILE``: this host's share of the stack, as a launch profile says
(:mod:`papf.launch.host`; profiles in ``papf/launch/profiles/``, format in docs/robot.md)."""

from __future__ import annotations

import json

from common.params import PORT, arg_type
from common.ros_link import (
    add_face_args,
    add_ros_args,
    cmd_vel_type,
    face_distro,
    face_domain,
    ros_distro,
    ros_domain,
)
from nodes.energy_meter.models import DEFAULT_MODEL, MODELS
from nodes.planner.registry import PLANNERS
from papf.cli.options import add_port_range, use_ports
from papf.cli.view import add_view_flag


def register(sub) -> None:
    p = sub.add_parser("launch", help="start this host's part of the stack from a profile",
                       description="Profiles: sim, robot, laptop, hil-robot, hil-laptop (or a "
                                   ".toml path). Exit code as `papf run` for profiles that drive "
                                   "a run; 0 after Ctrl-C for the others.")
    p.add_argument("profile", help="packaged profile name or .toml path")
    p.add_argument("--connect", action="append", default=[], metavar="ENDPOINT",
                   help="where this host's nodes connect, e.g. tcp/192.168.1.10:7447")
    p.add_argument("--listen", action="append", default=[], metavar="ENDPOINT",
                   help="the router's endpoints (profiles with a router), e.g. "
                        "tcp/0.0.0.0:7447 (every interface: the other host reaches it)")
    p.add_argument("--port", type=arg_type("--port", PORT),
                   help="the router's port on the profile's interface (robot: tcp/0.0.0.0:PORT, "
                        "sim: tcp/127.0.0.1:PORT); default 7447, or a free one")
    add_port_range(p)
    p.add_argument("--namespace", default="rosbot", help="robot key namespace (rosbot)")
    p.add_argument("--join", action="append", default=[], metavar="ENDPOINT",
                   help="connect this host's router to another's (a fleet across hosts: one "
                        "Zenoh network, each robot under its own --namespace)")
    p.add_argument("--bridge-namespace", help="zenoh-bridge-ros2dds namespace (default none)")
    p.add_argument("--zenoh-config", metavar="FILE", help="Zenoh config of the nodes (secure split)")
    p.add_argument("--router-config", metavar="FILE", help="Zenoh config of the router")
    p.add_argument("--world", help="world (runs; robot side: its start pose)")
    p.add_argument("--planner", help=" | ".join(PLANNERS))
    p.add_argument("--seed", type=int)
    p.add_argument("--objects", choices=("none", "truth", "tracker"),
                   help="obstacle tracks for the planner: sim ground truth (sim, HIL), the "
                        "tracker node, or none (default for iapf: truth where a sim runs, "
                        "else tracker; none for the other planners)")
    p.add_argument("--record", metavar="F.mcap", help="record every message here")
    p.add_argument("--force", action="store_true", help="replace the --record file if it exists")
    p.add_argument("--format", choices=("mcap", "ros2"), default="mcap",
                   help="--record as mcap (default) or ros2 (a rosbag2 directory)")
    p.add_argument("--energy-model", choices=sorted(MODELS),
                   help=f"the live meter's model (default {DEFAULT_MODEL}, in every profile)")
    p.add_argument("--realtime", action="store_true",
                   help="sim profile: pace sim time to the wall clock (to watch, steer with "
                        "papf goal, or drive with papf teleop)")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="planner parameter, repeatable")
    p.add_argument("--timeout", type=float, default=300.0, metavar="S", help="run-time limit (300)")
    p.add_argument("--stall-timeout", type=float, default=20.0, metavar="S",
                   help="fail a run after S wall seconds without the driver's clock (20)")
    p.add_argument("--startup-timeout", type=float, default=60.0, metavar="S")
    p.add_argument("--json", action="store_true", help="print the run summary as one JSON object")
    p.add_argument("--dry-run", action="store_true", help="print the resolved process list as JSON, start nothing")
    p.add_argument("--verbose", "-v", action="store_true", help="show every node's log lines")
    # trust and a laptop that comes back (docs/robot.md "Pairing", "A laptop that comes back")
    p.add_argument("--key", metavar="FILE",
                   help="robot/laptop split: the pairing key both sides seal with (the robot "
                        "side makes FILE when missing; copy it to the laptop). Default: this "
                        "host's own, so a split on one host needs none")
    crash = p.add_mutually_exclusive_group()
    crash.add_argument("--resume", dest="after_crash", action="store_const", const="resume",
                       help="laptop: the robot is still in the run of a launcher that died: go "
                            "on with it (same run, clock, charge, goal)")
    crash.add_argument("--new-run", dest="after_crash", action="store_const", const="new",
                       help="laptop: the robot is still in a dead launcher's run: start a new "
                            "run from where the robot stands (fresh clock and meter)")
    add_view_flag(p)
    add_ros_args(p)
    add_face_args(p)
    p.set_defaults(func=cmd_launch)


def cmd_launch(args) -> int:
    from papf.launch.host import launch  # zenoh: only when launching
    from papf.launch.profile import LaunchOptions

    use_ports(args)   # --port-range for every process of this host, before any starts
    if args.port is not None:
        args.listen = router_listen(args.profile, args.port, args.listen)

    cmd_vel_type(args)
    domain = ros_domain(args) if args.ros == "rmw_zenoh" else None   # checked before any process
    values = {"world": args.world, "planner": args.planner, "seed": args.seed,
              "record": args.record, "energy_model": args.energy_model,
              "bridge_namespace": args.bridge_namespace, "view": args.view,
              "realtime": "1" if args.realtime else None,
              "objects": args.objects, "ros": args.ros, "cmd_vel_type": args.cmd_vel_type,
              "ros_domain": domain, "ros_face_domain": face_domain(args),
              "ros_face": "1" if args.ros_face else None,
              "ros_face_distro": face_distro(args) if args.ros_face else None,
              "record_format": "ros2" if args.record and args.format == "ros2" else None,
              "ros_distro": ros_distro(args) if args.ros == "rmw_zenoh" else None,
              "record_force": "1" if args.force else None}
    opt = LaunchOptions(args.profile, args.connect, args.listen, args.namespace, args.zenoh_config,
                        args.router_config, {k: v for k, v in values.items() if v is not None},
                        [x for kv in args.set for x in ("--set", kv)], args.timeout,
                        startup_timeout_s=args.startup_timeout, stall_s=args.stall_timeout,
                        verbose=args.verbose, dry_run=args.dry_run, join=args.join,
                        key_file=args.key, after_crash=args.after_crash or "refuse")
    result = launch(opt)
    if result is None:
        return 0
    if args.json:
        print(json.dumps(result.to_json()), flush=True)
    else:
        print(f"papf launch {args.profile}: {result.outcome} after {result.sim_time_s:.2f} s "
              f"({result.path_length_m:.2f} m, {result.charge_mAh:.2f} mAh) {result.reason}")
    return 130 if result.reason == "interrupted" else result.exit_code


def router_listen(profile: str, port: int, listen: list[str]) -> list[str]:
    """``--port P``: the profile's router endpoints with port P (ConfigError, exit 2, for a
    profile without a router, or beside ``--listen``, which says it all)."""
    import re

    from common.errors import ConfigError
    from papf.launch import portrange
    from papf.launch.profile import load_profile

    if listen:
        raise ConfigError("--port and --listen both set the router's endpoint: give one "
                          "(--listen tcp/HOST:PORT, or --port PORT on the profile's interface)")
    prof = load_profile(profile)
    if not prof.router:
        raise ConfigError(f"profile {prof.name} runs no router, so --port has nothing to set; "
                          "reach the other host's with --connect tcp/<host>:PORT")
    portrange.check_port(port)
    return [re.sub(r":\d+$", f":{port}", ep) for ep in prof.listen]
