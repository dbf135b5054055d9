"""``papf rosbot-emulator``: the ROSbot behind zenoh-bridge-ros2dds or on rmw_zenoh (:mod:`papf.robot.emulator`)."""

from __future__ import annotations

from common.params import RATE_HZ, SEED, arg_type, integer, num
from common.ros_link import add_ros_args
from common.transport import add_zenoh_args


def register(sub) -> None:
    """Add ``papf rosbot-emulator`` and its options to the subcommands ``sub``."""
    p = sub.add_parser("rosbot-emulator",
                       help="emulate the ROSbot behind zenoh-bridge-ros2dds or on rmw_zenoh",
                       description="Subscribe CDR cmd_vel, drive a unicycle with the ROSbot's "
                                   "limits, publish CDR odometry/filtered, battery (and scan "
                                   "with --world), as the real robot does through the bridge "
                                   "(--ros bridge) or on rmw_zenoh (--ros rmw_zenoh).")
    p.add_argument("--bridge-namespace", default="", metavar="NS",
                   help="bridge namespace of the emulated topics (default: none)")
    p.add_argument("--world", help="world the robot stands in: scan it (start pose too)")
    p.add_argument("--no-scan", action="store_true", help="no LaserScan even with --world")
    p.add_argument("--scan-beams", type=arg_type("--scan-beams", integer(1, 100_000)), default=720, help="LaserScan readings (720)")
    p.add_argument("--seed", type=arg_type("--seed", SEED), default=0, help="scan noise seed (0)")
    p.add_argument("--rate", type=arg_type("--rate", RATE_HZ), default=50.0, help="odometry rate [Hz] (50)")
    p.add_argument("--cmd-timeout", type=arg_type("--cmd-timeout", num(0.0, 10.0, "s")), default=0.5, metavar="S",
                   help="controller cmd_vel_timeout [s] (0.5; 0 = never)")
    p.add_argument("--battery-voltage", type=arg_type("--battery-voltage", num(0.0, 30.0, "V")), default=12.0, metavar="V",
                   help="pack voltage reported on battery (12.0)")
    p.add_argument("--trace", metavar="FILE", help="append a JSON line per command received")
    p.add_argument("--log-level", default="INFO")
    add_ros_args(p)
    add_zenoh_args(p)
    p.set_defaults(func=cmd_emulator)


def cmd_emulator(args) -> int:
    """``papf rosbot-emulator``: emulate the ROSbot until stopped; the exit code."""
    from papf.robot.emulator import run  # rosbags (the CDR codec): only when emulating

    return run(args)
