"""``papf plan``: a planner on a world offline, no processes (:mod:`papf.plan`)."""

from __future__ import annotations

import json


def register(sub) -> None:
    p = sub.add_parser("plan", help="run a planner on a world offline (no processes)",
                       description="Run the planner core on a world without the process "
                       "stack: 2-D worlds with the simulated LiDAR and a unicycle with the "
                       "ROSbot limits, 3-D worlds (spheres) with a point robot. Exit code: "
                       "0 reached, 3 stagnated, 4 collision, 5 timeout, 6 failed, 2 usage.")
    p.add_argument("--world", required=True, help="packaged world name or path to a .toml")
    p.add_argument("--planner", default="apf", help="apf | papf | arapf | wang (default apf)")
    p.add_argument("--seed", type=int, default=0, help="LiDAR noise seed (default 0)")
    p.add_argument("--timeout", type=float, default=300.0, metavar="S",
                   help="sim-time limit [s] (default 300)")
    p.add_argument("--dt", type=float, default=0.1, metavar="S", help="control period [s] (0.1)")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="planner parameter override, repeatable (e.g. --set v_max=0.3)")
    p.add_argument("--params", metavar="FILE.toml", help="planner parameters from a TOML file")
    p.add_argument("--plot", metavar="OUT.png",
                   help="write a PNG: world, path, footprints, and the planner's prediction, "
                        "abandoned predictions, top quarks and temporary goal at its most "
                        "telling cycle")
    p.add_argument("--out", metavar="PATH.csv|.json", help="write the path (CSV or JSON)")
    p.add_argument("--json", action="store_true", help="print one JSON summary object")
    p.set_defaults(func=cmd_plan)


def cmd_plan(args) -> int:
    from papf.monitor import EXIT_CODES
    from papf.plan import plan, write_path  # pybullet: only when planning
    from worlds import load_world

    world = load_world(args.world)
    result = plan(world, args.planner, params=args.set, seed=args.seed, max_time_s=args.timeout,
                  dt=args.dt, params_file=args.params, keep_states=bool(args.plot))
    if args.out:
        write_path(result, args.out)
    if args.plot:  # matplotlib: only with --plot
        title = f"{world.name}: {args.planner} (offline, seed {args.seed})"
        if world.dims == 2:  # with the planner's mind and the robot's footprint
            from papf.mind_plots import plot_plan

            plot_plan(world, result, args.plot, title)
        else:
            from papf.plots import plot_paths

            plot_paths(world, {f"{args.planner} ({result.outcome})": result.path}, args.plot,
                       title)
    s = result.summary()
    if args.json:
        print(json.dumps(s))
    else:
        print(f"{s['world']} {s['planner']}: {s['outcome']} after {s['duration_s']:.1f} s, "
              f"{s['path_length_m']:.2f} m, min clearance {s['min_clearance_m']:.2f} m"
              + (f" ({s['reason']})" if s["reason"] else ""))
    return EXIT_CODES.get(result.outcome, 6)
