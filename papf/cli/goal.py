"""``papf goal X Y``: send the planner a goal and follow it to an outcome (:mod:`papf.bus.goal`)."""

from __future__ import annotations

import sys

from common.errors import ConfigError
from common.params import arg_type, num
from common.robot import GOAL_TOLERANCE_MIN_M
from common.transport import StopRequested, add_zenoh_args
from schemas import Keys
from worlds import MAX_COORD_M

# A goal within the world's span (worlds.MAX_COORD_M): nan, inf or 1e308 are refused at once.
GOAL_COORD = num(-MAX_COORD_M, MAX_COORD_M, "m")
# A tolerance of 0 or 1e-300 m is never reached: the floor is common.robot's.
GOAL_TOLERANCE = num(GOAL_TOLERANCE_MIN_M, 100.0, "m")


def register(sub) -> None:
    """Add ``papf goal`` and its options to the subcommands ``sub``."""
    p = sub.add_parser("goal", help="send the planner a goal and follow it to an outcome",
                       description="Publish a goal until the planner acknowledges it, then "
                                   "follow its status: exit 0 reached, 3 stagnated, 4 collision, "
                                   "5 timeout, 6 failed or no planner. In a `papf launch` "
                                   "session this re-targets the running planner; with nodes "
                                   "started alone, --start-run also starts the run.")
    p.add_argument("x", type=arg_type("x", GOAL_COORD), nargs="?", help="goal x [m] in the world frame")
    p.add_argument("y", type=arg_type("y", GOAL_COORD), nargs="?", help="goal y [m]")
    p.add_argument("--world", help="take the goal (and tolerance) of this world instead")
    p.add_argument("--tolerance", type=arg_type("--tolerance", GOAL_TOLERANCE),
                   help="[m] (default 0.1, or the world's)")
    p.add_argument("--start-run", action="store_true",
                   help="publish run_started after the acknowledgement (nodes started alone)")
    p.add_argument("--no-wait", action="store_true", help="return once the planner acknowledged")
    p.add_argument("--timeout", type=arg_type("--timeout", num(0.0, 1e6, "s")), default=0.0,
                   metavar="S",
                   help="exit 5 without an outcome after S wall seconds (default: none)")
    add_zenoh_args(p)
    p.set_defaults(func=cmd_goal)


def _session(args):
    from papf.bus.session import open_session  # zenoh: only when connecting

    return open_session(args)


def cmd_goal(args) -> int:
    """``papf goal``: send a goal and follow it; 0 reached, 3 stagnated, 4 collision, ..."""
    from papf.bus.goal import send_goal

    if args.world:
        if args.x is not None:
            raise ConfigError("give either X Y or --world W, not both")
        from worlds import load_world

        world = load_world(args.world)
        x, y = world.goal[:2]
        tol = args.tolerance if args.tolerance is not None else world.tolerance
    elif args.x is None or args.y is None:
        raise ConfigError("give the goal as X Y [m] (e.g. papf goal 9 0) or --world W")
    else:
        x, y, tol = args.x, args.y, 0.1 if args.tolerance is None else args.tolerance
    if not tol >= GOAL_TOLERANCE_MIN_M:
        raise ConfigError(f"--tolerance {tol}: must be at least {GOAL_TOLERANCE_MIN_M:g} m "
                          "(a smaller tolerance is never reached)")
    stop = StopRequested()
    with _session(args) as s:
        res = send_goal(s, Keys(args.namespace), x, y, tol, start_run=args.start_run,
                        wait=not args.no_wait, timeout_s=args.timeout, out=_out,
                        stop=lambda: bool(stop))
    if res.outcome not in ("acknowledged", "reached"):
        print(f"papf goal: {res.outcome}: {res.reason}", file=sys.stderr)
    return res.exit_code




def _out(line: str) -> None:
    print(line, flush=True)
