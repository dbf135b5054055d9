"""``papf export foxglove IN.mcap OUT.mcap``: a recording as the live view's Foxglove
channels (:mod:`papf.recording.foxglove_export`; why an export: docs/recording.md).
``papf export ros2 IN.mcap OUT_DIR``: a recording as a rosbag2 of the ROS 2 face's topics
(:mod:`papf.recording.ros2_export`).
``papf export map WORLD OUT.yaml``: a world as a ROS map (:mod:`worlds.map_world`)."""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path


def register(sub) -> None:
    """Add ``papf export foxglove|ros2|map`` and their options to the subcommands ``sub``."""
    p = sub.add_parser("export", help="convert a recording for another tool")
    formats = p.add_subparsers(dest="format", required=True, metavar="FORMAT")
    f = formats.add_parser("foxglove", help="a recording as Foxglove's own channels (MCAP)",
                           description="Write OUT.mcap with the live view's channels "
                           "(LaserScan, FrameTransforms, PoseInFrame, SceneUpdate, Log, JSON "
                           "plots), JSON with Foxglove's JSON Schemas; Foxglove opens it.")
    f.add_argument("src", metavar="IN.mcap")
    f.add_argument("dst", metavar="OUT.mcap")
    f.add_argument("--world", help="world to draw (default: the recording's metadata)")
    f.add_argument("--force", action="store_true", help="replace OUT.mcap if it exists")
    f.set_defaults(func=cmd_export_foxglove)
    r = formats.add_parser("ros2", help="a recording as a rosbag2 (ros2 bag play, rosbags, Foxglove)",
                           description="Write the new directory OUT_DIR: a rosbag2 (metadata.yaml "
                           "+ MCAP, ros2msg schemas, CDR) of /scan, /odom, /tf, /tf_static, "
                           "/cmd_vel, /battery, /plan, /markers and /robot_description, stamped "
                           "in the recording's (sim) time. OUT_DIR must not exist.")
    r.add_argument("src", metavar="IN.mcap")
    r.add_argument("dst", metavar="OUT_DIR")
    r.set_defaults(func=cmd_export_ros2)
    m = formats.add_parser("map", help="a world as a ROS map (Nav2 map_server YAML + PGM)",
                           description="Write OUT.yaml and OUT.pgm beside it (trinary, "
                           "free 254, occupied 0): every obstacle of WORLD at t = 0, so Nav2 "
                           "and `papf run --world OUT.yaml` use the same world. Never overwrites.")
    m.add_argument("world", metavar="WORLD", help="packaged world name, .toml or map .yaml")
    m.add_argument("dst", metavar="OUT.yaml")
    m.add_argument("--resolution", type=float, default=0.05, help="[m/cell] (default 0.05)")
    m.set_defaults(func=cmd_export_map)


def cmd_export_map(args: argparse.Namespace) -> int:
    """``papf export map``: a world as a ROS map (YAML + PGM); the exit code."""
    from common.errors import WorldError
    from worlds import World, load_world
    from worlds.kinds.grid import from_map
    from worlds.map_world import is_map, rasterize
    from worlds.maps import load_map, save_map

    if not (math.isfinite(args.resolution) and 0.001 <= args.resolution <= 10.0):
        raise WorldError(f"--resolution {args.resolution!r}: give 0.001 .. 10 m per cell")
    if Path(args.dst).suffix.lower() not in (".yaml", ".yml"):
        raise WorldError(f"{args.dst!r}: the map's file name ends in .yaml (its image: .pgm beside it)")
    if is_map(args.world):
        grid = load_map(args.world)   # the map again (e.g. at another resolution)
        corner = grid.origin[:2]
        world = World(Path(args.world).stem, "", (*corner, 0.0), corner, 0.1,
                      (from_map(grid, 0.5),), source=args.world)
    else:
        world = load_world(args.world)
    if world.dims != 2:
        raise WorldError(f"world {args.world!r} is 3-D; a ROS map is a 2-D occupancy grid")
    try:
        yaml_path, pgm = save_map(rasterize(world, args.resolution), args.dst)
    except FileExistsError as exc:
        raise WorldError(str(exc)) from None
    print(f"{yaml_path} + {pgm.name}: {args.world} at {args.resolution:g} m/cell")
    return 0


def cmd_export_foxglove(args: argparse.Namespace) -> int:
    """``papf export foxglove``: a recording as Foxglove's channels (MCAP); the exit code."""
    from papf.recording.foxglove_export import export_foxglove

    stats = export_foxglove(args.src, args.dst, args.world, force=args.force)
    for note in stats.notes:
        print(f"papf export: {note}", file=sys.stderr)
    print(f"{args.dst}: {stats.written} Foxglove messages from {stats.read} recorded "
          f"({stats.skipped} skipped), world {stats.world or 'none'}")
    return 0


def cmd_export_ros2(args: argparse.Namespace) -> int:
    """``papf export ros2``: a recording as a rosbag2; the exit code."""
    from papf.recording.ros2_export import export_ros2

    stats = export_ros2(args.src, args.dst)
    topics = ", ".join(f"{t} {n}" for t, n in sorted(stats.written.items()))
    print(f"{args.dst}: rosbag2 with {sum(stats.written.values())} ROS 2 messages from "
          f"{stats.read} recorded ({stats.skipped} not on the ROS 2 face): {topics}")
    return 0
