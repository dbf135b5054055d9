"""``papf teleop``: drive the robot from the keyboard, through the driver's limits and watchdog
(:mod:`papf.bus.teleop`)."""

from __future__ import annotations

import sys

from common import robot
from common.params import RATE_HZ, arg_type, pos
from common.transport import add_zenoh_args
from schemas import Keys


def register(sub) -> None:
    """Add ``papf teleop`` and its options to the subcommands ``sub``."""
    from papf.bus.teleop import HELP  # no zenoh, no terminal: cheap

    p = sub.add_parser("teleop", help="drive the robot with the keyboard (cmd_vel, in a terminal)",
                       description="Keyboard teleoperation on <ns>/cmd_vel, through the base "
                                   "driver's limits and 0.5 s watchdog like the planner's "
                                   f"commands. Keys: {HELP}. Run no planner at the same time "
                                   "(both would command the robot).")
    p.add_argument("--max-v", type=arg_type("--max-v", pos(robot.V_MAX_M_S, "m/s")), default=0.3, metavar="M_S",
                   help="teleop speed limit [m/s] (default 0.3; the driver's is 0.9)")
    p.add_argument("--max-w", type=arg_type("--max-w", pos(robot.W_MAX_RAD_S, "rad/s")), default=1.0, metavar="RAD_S",
                   help="teleop turn-rate limit [rad/s] (default 1.0; the driver's is 3.0)")
    p.add_argument("--step-v", type=arg_type("--step-v", pos(robot.V_MAX_M_S, "m/s")), default=0.05, help="[m/s] per key press (0.05)")
    p.add_argument("--step-w", type=arg_type("--step-w", pos(robot.W_MAX_RAD_S, "rad/s")), default=0.2, help="[rad/s] per key press (0.2)")
    p.add_argument("--rate", type=arg_type("--rate", RATE_HZ), default=10.0, help="commands per second (10)")
    p.add_argument("--start-run", action="store_true",
                   help="publish run_started first (a world simulator started alone waits for it)")
    add_zenoh_args(p)
    p.set_defaults(func=cmd_teleop)


def _session(args):
    from papf.bus.session import open_session  # zenoh: only when connecting

    return open_session(args)


def cmd_teleop(args) -> int:
    """``papf teleop``: drive the robot with the keyboard; the exit code."""
    from papf.bus.teleop import TeleopState, run

    state = TeleopState(args.max_v, args.max_w, args.step_v, args.step_w)
    if not args.rate > 0:
        print("papf teleop: --rate must be > 0", file=sys.stderr)
        return 2
    with _session(args) as s:
        return run(s, Keys(args.namespace), state, period_s=1.0 / args.rate,
                   start_run=args.start_run)
