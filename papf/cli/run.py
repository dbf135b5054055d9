"""``papf run``: the whole simulated stack once, to an outcome (:mod:`papf.launch.run`)."""

from __future__ import annotations

import json

from common.drive import DRIVER_OPTIONS
from common.params import PORT, SEED, TIMEOUT, arg_type
from common.ros_link import add_face_args, face_distro, face_domain
from common.units import LOCKSTEP_TIMEOUT_S
from nodes.energy_meter.models import DEFAULT_MODEL, MODELS
from papf.cli.options import (
    add_planner_settings,
    add_port_range,
    add_world_and_planner,
    resolve_world,
    use_ports,
)
from papf.cli.view import add_view_flag


def register(sub) -> None:
    p = sub.add_parser("run", help="run the whole simulated stack once, to an outcome",
                       description="Start the processes of the `sim` launch profile (router, "
                                   "world_sim (as base_driver), lidar_sim, planner, energy_meter, and the "
                                   "recorder with --record); drive to the world's goal; print a "
                                   "summary. Exit code: 0 reached, 3 stagnated, 4 collision, "
                                   "5 timeout, 6 failed, 2 usage error.")
    add_world_and_planner(p)
    p.add_argument("--seed", type=arg_type("--seed", SEED), default=0,
                   help="seed of all noise (default 0)")
    p.add_argument("--record", metavar="F.mcap", help="record every message to this MCAP file")
    p.add_argument("--force", action="store_true", help="replace the --record file if it exists")
    p.add_argument("--format", choices=("mcap", "ros2"), default="mcap",
                   help="--record as mcap (default: every message) or ros2 (a rosbag2 "
                        "directory of the ROS 2 face's topics: ros2 bag play, papf report)")
    p.add_argument("--timeout", type=arg_type("--timeout", TIMEOUT), default=300.0, metavar="S",
                   help="sim-time limit in seconds (default 300)")
    p.add_argument("--realtime", action="store_true", help="pace sim time to the wall clock")
    p.add_argument("--json", action="store_true", help="print one JSON object, nothing else")
    p.add_argument("--port", type=arg_type("--port", PORT),
                   help="embedded router port (default 7447, or a free one)")
    add_port_range(p)
    p.add_argument("--namespace", default="rosbot", help="robot key namespace")
    p.add_argument("--zenoh-mode", choices=("client", "peer"), default="peer",
                   help="nodes' Zenoh mode: peer (direct loopback links, the launcher's router "
                        "only for discovery; default) or client (all through the router)")
    p.add_argument("--energy-model", choices=sorted(MODELS), default=DEFAULT_MODEL,
                   help=f"the live meter's model (default {DEFAULT_MODEL}; docs/energy.md)")
    add_planner_settings(p)
    p.add_argument("--preset", choices=("default", "paper"), default="default",
                   help="planner preset: default (our improvements) or paper (the paper read "
                        "literally, docs/planners.md \"Presets\")")
    p.add_argument("--continue-on-collision", action="store_true",
                   help="count collisions but keep driving (default: a collision ends the run)")
    p.add_argument("--objects", choices=("none", "truth", "tracker"),
                   help="obstacle tracks for the planner: the sim's ground truth, the tracker "
                        "node on the scans, or none (default: truth for iapf, else none)")
    p.add_argument("--passing", choices=("orca", "off"),
                   help="a fleet's robots pass each other: orca (default with two or more "
                        "robots; each planner gets the others as --objects) or off")
    p.add_argument("--odom-hz", type=arg_type("--odom-hz", DRIVER_OPTIONS["odom_hz"]),
                   metavar="HZ", help="the sim's odometry, wheels and battery rate (default 50; a "
                   "fleet's without people: the scan rate, 10; docs/performance.md \"A fleet's odometry rate\")")
    p.add_argument("--lockstep-timeout", type=arg_type("--lockstep-timeout",
                                                        DRIVER_OPTIONS["lockstep_timeout"]),
                   default=LOCKSTEP_TIMEOUT_S, metavar="S",
                   help="wall seconds the simulator waits for a scan's command "
                   "before it gives up the lockstep (default 2; longer on a loaded machine: a "
                   "run is bit-reproducible only while the lockstep holds)")
    p.add_argument("--dry-run", action="store_true",
                   help="print the resolved process list as JSON, start nothing")
    p.add_argument("--verbose", "-v", action="store_true", help="show every node's log lines")
    add_view_flag(p)
    add_face_args(p)
    add_link_args(p)
    p.set_defaults(func=cmd_run)


def add_link_args(p) -> None:
    """``--link``: the split stack over an emulated link (papf.launch.split, docs/link.md)."""
    p.add_argument("--link", metavar="PROFILE|SPEC",
                   help="run the robot side and the laptop side on their own routers, joined "
                        "through papf link: a profile (lan, wifi, wifi-bad, lte) and/or "
                        "key=value items, e.g. wifi,outage=10@20 or delay=200,jitter=150 "
                        "(real time; outages count from the run's start; docs/link.md)")
    p.add_argument("--robot-trace", metavar="FILE",
                   help="with --link: append a JSON line per command the emulated robot "
                        "received (monotonic time, v, w)")
    p.add_argument("--robot-record", metavar="F.mcap",
                   help="with --link: the robot side's own recording (its black box: every "
                        "command it obeyed or refused, odometry, scans; docs/link-driving.md)")


def run_config(args):
    """The :class:`papf.launch.run.RunConfig` of parsed ``papf run`` options."""
    from nodes.planner.registry import preset_sets
    from papf.launch.run import RunConfig  # zenoh: only when a run is made

    resolve_world(args)
    planner_args = [x for kv in (*preset_sets(args.preset), *args.set) for x in ("--set", kv)]
    if args.params:
        planner_args += ["--params", args.params]
    return RunConfig(world=args.world, planner=args.planner, seed=args.seed,
                     timeout_s=args.timeout, realtime=args.realtime, record=args.record,
                     force=args.force, port=args.port, namespace=args.namespace, planner_args=planner_args,
                     energy_model=args.energy_model,
                     stop_on_collision=not args.continue_on_collision, verbose=args.verbose,
                     zenoh_mode=args.zenoh_mode, objects=args.objects, view=args.view,
                     passing=args.passing, odom_hz=args.odom_hz,
                     lockstep_timeout_s=args.lockstep_timeout,
                     ros_face=face_domain(args), progress=None if not args.json else False,
                     link=args.link, robot_trace=args.robot_trace,
                     robot_record=args.robot_record,
                     ros_face_distro=face_distro(args), record_format=args.format)


def cmd_run(args) -> int:
    from papf.launch.run import preflight, resolve_run, run

    use_ports(args)   # --port-range: for every process of the run, before any starts

    if args.link is not None:
        return cmd_run_link(args)
    if args.robot_trace:
        from common.errors import ConfigError

        raise ConfigError("--robot-trace traces the emulated robot of a split run: add --link")
    if args.robot_record:
        from common.errors import ConfigError

        raise ConfigError("--robot-record records the robot side of a split run: add --link")
    if args.dry_run:  # the `sim` profile's processes (port: --port, else 7447), preflighted
        cfg = run_config(args)
        preflight(cfg)
        print(resolve_run(cfg).to_json())
        return 0
    result = run(run_config(args))
    if args.json:
        print(json.dumps(result.to_json()))
    else:
        print_summary(result, args.energy_model)
    return result.exit_code


def cmd_run_link(args) -> int:
    """``papf run --link``: the split stack over papf link (:mod:`papf.launch.split`)."""
    from papf.launch.split import resolve_split, run_split

    cfg = run_config(args)
    if args.dry_run:
        print(resolve_split(cfg))
        return 0
    result = run_split(cfg)
    if args.json:
        print(json.dumps(result.to_json()))
    else:
        print_summary(result, args.energy_model)
        if result.link_emulator:
            print(link_line(result.link_emulator))
    return 130 if result.reason == "interrupted" else result.exit_code


def link_line(stats: dict) -> str:
    """One line on what the emulated link did (``papf run --link``'s summary)."""
    out, back = stats["directions"]["out"], stats["directions"]["back"]
    p50 = (out["delay_ms"]["p50"] or 0.0, back["delay_ms"]["p50"] or 0.0)
    p99 = (out["delay_ms"]["p99"] or 0.0, back["delay_ms"]["p99"] or 0.0)
    return (f"link: {stats['description']}; one-way delay p50 {p50[0]:.0f}/{p50[1]:.0f} ms, "
            f"p99 {p99[0]:.0f}/{p99[1]:.0f} ms (laptop->robot/robot->laptop); "
            f"{len(stats['outages'])} outage(s), {stats['outage_s']:.1f} s down")


def print_summary(result, energy_model: str | None = None) -> None:
    """The run's table (and a fleet's, one row per robot); ``energy_model`` named beside the
    charge (the meter's model: its figures differ from the paper's model's)."""
    from rich.markup import escape  # values are text: a "[...]" in them is no style tag
    from rich.table import Table

    from common.text import safe_text
    from papf.console.tables import print_table  # rich: only to print a table

    colour = "green" if result.outcome == "reached" else "red"
    t = Table(title=f"papf run: [{colour}]{result.outcome}[/]", show_header=False)
    rows = [("world", result.world), ("planner", result.planner), ("seed", str(result.seed)),
            ("duration", f"{result.duration_s:.2f} s"),
            ("path length", f"{result.path_length_m:.2f} m"),
            ("charge", f"{result.charge_mAh:.2f} mAh"
                       + (f" ({energy_model} model)" if energy_model else "")),
            ("energy", f"{result.energy_J:.1f} J"),
            ("collisions", str(result.collisions)), ("sim time", f"{result.sim_time_s:.2f} s"),
            ("wall time", f"{result.wall_time_s:.2f} s  "
                          f"({result.sim_time_s / max(result.wall_time_s, 1e-9):.1f}x real time)")]
    if result.fleet:
        sep = result.min_separation_m
        rows.insert(8, ("min separation", "-" if sep is None else f"{sep:.3f} m"))
    if result.reason:
        rows.append(("reason", result.reason))
    rows += fault_rows(result.faults)
    for k, v in rows:   # a reason may quote a node's output: no markup, no ESC (common.text)
        t.add_row(k, escape(safe_text(v, None)))
    print_table(t)   # fits: whole cells on a narrow terminal, one line a row when piped
    if result.fleet:
        print_table(fleet_table(result.fleet))


def fault_rows(faults: tuple[str, ...]) -> list[tuple[str, str]]:
    """The summary's rows on the run's node faults: the first, how many, and what a broken
    lockstep means and what to do about it."""
    from nodes.world_sim.loop import LOCKSTEP_FAULT

    if not faults:
        return []
    more = f" (and {len(faults) - 1} more: --json lists them)" if len(faults) > 1 else ""
    rows = [("faults", faults[0] + more)]
    if any(LOCKSTEP_FAULT in f for f in faults):
        rows.append(("lockstep", "broken: this run is not bit-reproducible (a command came "
                                 "later than the simulator waits; a loaded machine? papf run "
                                 "--lockstep-timeout S)"))
    return rows


def fleet_table(robots: tuple[dict, ...]):
    """One row per robot of a fleet's run (``papf run --json``'s ``robots``)."""
    from rich.markup import escape
    from rich.table import Table

    def num(v, fmt: str) -> str:
        return "-" if v is None else format(v, fmt)

    t = Table(title="robots")
    for col in ("robot", "planner", "outcome", "time s", "path m", "mAh", "coll.", "sep. m",
                "disc. s"):
        t.add_column(col, justify="left" if col in ("robot", "planner", "outcome") else "right")
    for r in robots:
        colour = "green" if r["outcome"] == "reached" else "red"
        t.add_row(escape(r["name"]), escape(r["planner"]), f"[{colour}]{escape(r['outcome'])}[/]",
                  num(r["duration_s"], ".2f"), num(r["path_length_m"], ".2f"),
                  num(r["charge_mAh"], ".2f"), str(r["collisions"]),
                  num(r["min_separation_m"], ".3f"), num(r["discomfort_s"], ".2f"))
    return t
