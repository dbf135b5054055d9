"""``papf animate FILE.mcap OUT.gif|OUT.mp4``: a recorded run as a moving picture
(:mod:`papf.report.animation`)."""

from __future__ import annotations

import argparse

from common.params import arg_type, integer, pos


def register(sub) -> None:
    """Add ``papf animate`` and its options to the subcommands ``sub``."""
    p = sub.add_parser("animate", help="render a recorded run as a GIF or MP4",
                       description="Top view (world, path, footprint, the planner's mind), "
                       "speed and charge over time; time, speed and charge in the title. "
                       "MP4 needs ffmpeg.")
    from papf.cli.report import add_topics_option

    p.add_argument("src", metavar="FILE.mcap|BAG")
    p.add_argument("out", metavar="OUT.gif|OUT.mp4")
    p.add_argument("--fps", type=arg_type("--fps", pos(120.0, "1/s")), default=10.0, help="frames per second (default 10)")
    p.add_argument("--speed", type=arg_type("--speed", pos(1e4)), default=4.0,
                   help="sim seconds per video second (default 4)")
    p.add_argument("--world", help="world to draw (default: the recording's metadata)")
    p.add_argument("--dpi", type=arg_type("--dpi", integer(10, 600)), default=110,
                   help="resolution [dots per inch] (default 110: 1210 x 616 pixels)")
    add_topics_option(p)
    p.add_argument("--force", action="store_true", help="replace OUT if it exists")
    p.set_defaults(func=cmd_animate)


def cmd_animate(args: argparse.Namespace) -> int:
    """``papf animate``: render a recorded run as a GIF or MP4; the exit code."""
    from papf.cli.report import topic_map
    from papf.report.animation import animate

    n = animate(args.src, args.out, args.fps, args.speed, args.world, args.dpi, args.force,
                topics=topic_map(args))
    print(f"{args.out}: {n} frames at {args.fps:g} fps ({args.speed:g}x)")
    return 0
