"""``papf export foxglove IN.mcap OUT.mcap``: a recording as the live view's Foxglove
channels (:mod:`papf.recording.foxglove_export`; why an export: docs/recording.md).
``papf export ros2 IN.mcap OUT_DIR``: a recording as a rosbag2 of the ROS 2 face's topics
(:mod:`papf.recording.ros2_export`)."""

from __future__ import annotations

import argparse
import sys


def register(sub) -> None:
    p = sub.add_parser("export", help="convert a recording for another tool")
    formats = p.add_subparsers(dest="format", required=True, metavar="FORMAT")
    f = formats.add_parser("foxglove", help="a recording as Foxglove's own channels (MCAP)",
                           description="Write OUT.mcap with the live view's channels "
                           "(LaserScan, FrameTransforms, PoseInFrame, SceneUpdate, Log, JSON "
                           "plots), JSON with Foxglove's JSON Schemas; Foxglove opens it.")
    f.add_argument("src", metavar="IN.mcap")
    f.add_argument("dst", metavar="OUT.mcap")
    f.add_argument("--world", help="world to draw (default: the recording's metadata)")
    f.set_defaults(func=cmd_export_foxglove)
    r = formats.add_parser("ros2", help="a recording as a rosbag2 (ros2 bag play, rosbags, Foxglove)",
                           description="Write the new directory OUT_DIR: a rosbag2 (metadata.yaml "
                           "+ MCAP, ros2msg schemas, CDR) of /scan, /odom, /tf, /tf_static, "
                           "/cmd_vel, /battery, /plan, /markers and /robot_description, stamped "
                           "in the recording's (sim) time. OUT_DIR must not exist.")
    r.add_argument("src", metavar="IN.mcap")
    r.add_argument("dst", metavar="OUT_DIR")
    r.set_defaults(func=cmd_export_ros2)


def cmd_export_foxglove(args: argparse.Namespace) -> int:
    from papf.recording.foxglove_export import export_foxglove

    stats = export_foxglove(args.src, args.dst, args.world)
    for note in stats.notes:
        print(f"papf export: {note}", file=sys.stderr)
    print(f"{args.dst}: {stats.written} Foxglove messages from {stats.read} recorded "
          f"({stats.skipped} skipped), world {stats.world or 'none'}")
    return 0


def cmd_export_ros2(args: argparse.Namespace) -> int:
    from papf.recording.ros2_export import export_ros2

    stats = export_ros2(args.src, args.dst)
    topics = ", ".join(f"{t} {n}" for t, n in sorted(stats.written.items()))
    print(f"{args.dst}: rosbag2 with {sum(stats.written.values())} ROS 2 messages from "
          f"{stats.read} recorded ({stats.skipped} not on the ROS 2 face): {topics}")
    return 0
