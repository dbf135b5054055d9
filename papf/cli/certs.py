"""``papf make-certs DIR``: a test CA, certificates and the Zenoh configs of the secure split."""

from __future__ import annotations

import sys

from common.ros_link import add_ros_args, ros_domain


def register(sub) -> None:
    """Add ``papf make-certs`` and its options to the subcommands ``sub``."""
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
    p.add_argument("--force", action="store_true",
                   help="replace an existing bundle in DIR (a new CA and new passwords)")
    add_ros_args(p, cmd_vel=False)   # rmw_zenoh: rmw_zenohd is the secure router (docs/robot.md)
    p.set_defaults(func=cmd_make_certs)


def cmd_make_certs(args) -> int:
    """``papf make-certs``: write the test CA, certificates and secure configs; the exit code."""
    from common.ros_link import BridgeTopics  # rosbags: only when writing configs
    from papf.robot.certs import where_files_go, write_bundle

    domain = ros_domain(args)
    b = write_bundle(args.dir, args.robot_host, args.namespace, BridgeTopics(args.bridge_namespace),
                     force=args.force, ros=args.ros, ros_domain=domain)
    if args.ros == "rmw_zenoh":
        robot = (f"(cd {b.dir} && ZENOH_ROUTER_CONFIG_URI=rmw_zenohd.json5 ros2 run rmw_zenoh_cpp "
                 "rmw_zenohd) &\n        ZENOH_SESSION_CONFIG_URI=<dir>/ros_session.json5 for "
                 "every ROS 2 process\n        papf launch robot --ros rmw_zenoh --ros-domain "
                 f"{domain} --router-config router.json5 --zenoh-config robot.json5 --listen "
                 "tcp/127.0.0.1:7449")
    else:
        robot = ("papf launch robot --router-config router.json5 --zenoh-config robot.json5 "
                 "--listen tcp/127.0.0.1:7447 --listen tls/0.0.0.0:7448")
    print(f"wrote {b.dir} (README.txt says the same):\n{where_files_go(args.ros)}"
          f"robot:  {robot}\n"
          "laptop: papf launch laptop --zenoh-config laptop.json5 --world W", file=sys.stderr)
    return 0
