"""``papf plan``: a planner on a world offline, no processes (:func:`papf.offline.run.simulate`)."""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

from common.errors import ConfigError
from common.params import SEED, TIMEOUT, arg_type, num
from nodes.planner.registry import car_variants, one_with_role
from papf.cli.options import (
    add_planner_settings,
    add_world_and_planner,
    planner_help,
    resolve_world,
)
from papf.offline.run import MOTIONS


def register(sub) -> None:
    """Add ``papf plan`` and its options to the subcommands ``sub``."""
    p = sub.add_parser("plan", help="run a planner on a world offline (no processes)",
                       description="Run the planner core on a world without the process "
                       "stack: 2-D worlds with the simulated LiDAR and a unicycle with the "
                       "ROSbot limits, 3-D worlds (spheres) with a point robot. Exit code: "
                       "0 reached, 3 stagnated, 4 collision, 5 timeout, 6 failed, 2 usage.")
    cars = ", ".join(f"{name} ({v[1]})" for name, v in car_variants().items())
    add_world_and_planner(p, f"{planner_help()}; on car-scale worlds (iapf-case-*): {cars}")
    p.add_argument("--seed", type=arg_type("--seed", SEED), default=0,
                   help="LiDAR noise seed (default 0)")
    p.add_argument("--timeout", type=arg_type("--timeout", TIMEOUT), default=300.0, metavar="S",
                   help="sim-time limit [s] (default 300)")
    p.add_argument("--dt", type=arg_type("--dt", num(0.001, 1.0, "s")), default=0.1, metavar="S", help="control period [s] (0.1)")
    add_planner_settings(p)
    p.add_argument("--preset", choices=("default", "paper"), default="default",
                   help="planner preset: default (our improvements) or paper (the paper literally)")
    p.add_argument("--motion", choices=MOTIONS, default="robot",
                   help="robot (default) or fixed-step: Wang's MATLAB point, step 0.5, J = 200, "
                        "the obstacles' centres known (planners "
                        f"{one_with_role('wang-baseline')} and {one_with_role('wang-proposed')} only)")
    p.add_argument("--passing", choices=("orca", "off"),
                   help="robots pass each other: orca (default with two or more [[robots]]; "
                        "each planner told the others' poses and velocities) or off")
    p.add_argument("--plot", metavar="OUT.png",
                   help="write a PNG: world, path, footprints, and the planner's prediction, "
                        "abandoned predictions, top quarks and temporary goal at its most "
                        "telling cycle")
    p.add_argument("--out", metavar="PATH.csv|.json", help="write the path (CSV or JSON)")
    p.add_argument("--force", action="store_true",
                   help="replace an existing --plot or --out file (never the world or --params)")
    p.add_argument("--json", action="store_true", help="print one JSON summary object")
    p.set_defaults(func=cmd_plan)


def cmd_plan(args) -> int:
    """``papf plan``: a planner on a world offline; the outcome's exit code."""
    from common.outcomes import EXIT_CODES
    from nodes.planner.registry import preset_sets
    from papf.offline.result import write_path
    from papf.offline.run import simulate  # pybullet: only when planning
    from worlds import load_world, world_path
    from worlds.checks import check_runnable

    given = args.world
    world = load_world(resolve_world(args))
    check_runnable(world)
    check_outputs(args, [given, world_path(args.world), args.params])   # before the run
    sets = [*preset_sets(args.preset), *args.set]
    result = simulate(world, args.planner, params=sets, seed=args.seed, max_time_s=args.timeout,
                      dt=args.dt, params_file=args.params, keep_states=bool(args.plot),
                      motion=args.motion, passing=args.passing)
    if args.out:
        write_path(result, args.out, force=True)   # checked above (check_outputs)
    if args.plot:  # matplotlib: only with --plot
        _plot(world, result, args)
    s = result.summary()
    if args.json:
        print(json.dumps(s))
    elif result.motion == "fixed-step":
        print(f"{s['world']} {s['planner']} (fixed step): {s['outcome']} after {s['cycles']} "
              f"iterations, path {s['path_length_m']:.2f} m, min clearance "
              f"{s['min_clearance_m']:.2f} m ({s['reason']})")
    else:
        print(f"{s['world']} {s['planner']}: {s['outcome']} after {s['duration_s']:.1f} s, "
              f"{s['path_length_m']:.2f} m, min clearance {s['min_clearance_m']:.2f} m"
              + (f" ({s['reason']})" if s["reason"] else ""))
    for r in s.get("robots", []):   # a crowd world: one line per robot
        sep = "-" if r["min_separation_m"] is None else f"{r['min_separation_m']:.2f} m"
        print(f"  {r['name']} {r['planner']}: {r['outcome']} after {r['duration_s']:.1f} s, "
              f"{r['path_length_m']:.2f} m, collisions wall/robot/person "
              f"{r['collisions_wall']}/{r['collisions_robot']}/{r['collisions_person']}, "
              f"min separation {sep}, discomfort {r['discomfort_s']:.1f} s, "
              f"intrusions {r['intrusions']}, irregularity "
              f"{r['path_irregularity_rad_per_m']:.2f} rad/m")
    for what, path in (("plot", args.plot), ("path", args.out)):
        if path:  # on stderr: with --json, stdout holds the one JSON object only
            print(f"{what}: {os.path.abspath(path)}", file=sys.stderr)
    return EXIT_CODES.get(result.outcome, 6)


def check_outputs(args, inputs) -> None:
    """``--plot`` and ``--out`` may be written (:func:`common.outfiles.check_output`): no
    existing file unless ``--force``, never an input (the world, ``--params``), not each other;
    OutputError/ConfigError (exit 2, one line) before the run."""
    from common.outfiles import OutputError, check_output, same_file

    inputs = [p for p in inputs if p and Path(p).is_file()]
    for flag, path in (("--plot", args.plot), ("--out", args.out)):
        if path:
            try:
                check_output(path, inputs, args.force)
            except OutputError as exc:
                raise OutputError(f"{flag} {exc}") from None
    if args.out and Path(args.out).suffix.lower() not in (".csv", ".json"):
        raise ConfigError(f"--out {args.out!r}: the path file's suffix must be .csv or .json")
    if args.plot and args.out and (Path(args.plot).absolute() == Path(args.out).absolute()
                                   or same_file(args.plot, args.out)):
        raise ConfigError("--plot and --out name the same file; give two")


def _plot(world, result, args) -> None:
    """The PNG of ``--plot``: the ROSbot's run with its mind, or the path alone."""
    if result.motion == "crowd":      # every robot and the people's tracks
        from papf.plots.crowd import plot_crowd

        run = result.trace
        plot_crowd(world, {f"{r.name} ({r.planner}, {r.result.outcome})": r.result.path
                           for r in run.robots}, run.people, run.radii, args.plot,
                   f"{world.name} (offline, seed {args.seed})", shown=run.shown)
        return
    if result.motion == "unicycle":   # with the mind and the ROSbot's footprint
        from papf.plots.mind import plot_plan

        plot_plan(world, result, args.plot, f"{world.name}: {args.planner} (offline, seed {args.seed})")
        return
    if world.vehicle == "car":     # a road: lanes, traffic over time, the finish line
        from papf.plots.road import plot_road_run

        plot_road_run(world, args.planner, result.outcome, result.path[:, :2], result.times,
                      args.plot, f"{world.name}: {args.planner} (offline, seed {args.seed})")
        return
    from papf.plots.paths import plot_paths

    label = f"{args.planner} ({result.outcome})"
    title = (f"{world.name}: {args.planner}, fixed step (Wang's simulation)"
             if result.motion == "fixed-step" else
             f"{world.name}: {args.planner} (offline, seed {args.seed})")
    times = None if result.motion == "fixed-step" else {label: result.times}   # iterations, no time
    plot_paths(world, {label: result.path}, args.plot, title, times=times)
