"""``papf plan``: a planner on a world offline, no processes (:mod:`papf.offline.plan`)."""

from __future__ import annotations

import json
import os
import sys

from common.params import SEED, TIMEOUT, arg_type
from papf.cli.options import add_planner_settings, add_world_and_planner


def register(sub) -> None:
    p = sub.add_parser("plan", help="run a planner on a world offline (no processes)",
                       description="Run the planner core on a world without the process "
                       "stack: 2-D worlds with the simulated LiDAR and a unicycle with the "
                       "ROSbot limits, 3-D worlds (spheres) with a point robot. Exit code: "
                       "0 reached, 3 stagnated, 4 collision, 5 timeout, 6 failed, 2 usage.")
    add_world_and_planner(p, "apf | papf | arapf | wang | iapf (default apf); on car-scale "
                             "worlds (iapf-case-*): iapf, iapf-np (no prediction), apf (the "
                             "paper's baseline)")
    p.add_argument("--seed", type=arg_type("--seed", SEED), default=0,
                   help="LiDAR noise seed (default 0)")
    p.add_argument("--timeout", type=arg_type("--timeout", TIMEOUT), default=300.0, metavar="S",
                   help="sim-time limit [s] (default 300)")
    p.add_argument("--dt", type=float, default=0.1, metavar="S", help="control period [s] (0.1)")
    add_planner_settings(p)
    p.add_argument("--preset", choices=("default", "paper"), default="default",
                   help="planner preset: default (our improvements) or paper (the paper literally)")
    p.add_argument("--motion", choices=("robot", "fixed-step"), default="robot",
                   help="robot (default) or fixed-step: Wang's MATLAB point, step 0.5, J = 200, "
                        "the obstacles' centres known (planners wang-apf and wang only)")
    p.add_argument("--plot", metavar="OUT.png",
                   help="write a PNG: world, path, footprints, and the planner's prediction, "
                        "abandoned predictions, top quarks and temporary goal at its most "
                        "telling cycle")
    p.add_argument("--out", metavar="PATH.csv|.json", help="write the path (CSV or JSON)")
    p.add_argument("--json", action="store_true", help="print one JSON summary object")
    p.set_defaults(func=cmd_plan)


def cmd_plan(args) -> int:
    from nodes.planner.registry import preset_sets
    from papf.launch.outcome import EXIT_CODES
    from papf.offline.plan import plan, write_path  # pybullet: only when planning
    from worlds import load_world
    from worlds.checks import check_runnable

    world = load_world(args.world)
    check_runnable(world, max_obstacles=sys.maxsize)   # offline: no obstacle limit
    if args.motion == "fixed-step":
        return _fixed_step(world, args)
    sets = [*preset_sets(args.preset), *args.set]
    if world.vehicle == "car":   # the IAPF paper's cases: its vehicle model, car scale
        from papf.offline.road import plan_car

        result = plan_car(world, args.planner, sets, args.params, max_time_s=args.timeout)
    else:
        result = plan(world, args.planner, params=sets, seed=args.seed,
                      max_time_s=args.timeout, dt=args.dt, params_file=args.params,
                      keep_states=bool(args.plot))
    if args.out:
        write_path(result, args.out)
    if args.plot:  # matplotlib: only with --plot
        title = f"{world.name}: {args.planner} (offline, seed {args.seed})"
        if world.dims == 2 and world.vehicle != "car":  # with the mind and the ROSbot's footprint
            from papf.plots.mind import plot_plan

            plot_plan(world, result, args.plot, title)
        elif world.vehicle == "car":     # a road: lanes, traffic over time, the finish line
            from papf.plots.road import plot_road_run

            plot_road_run(world, args.planner, result.outcome, result.path[:, :2], result.times,
                          args.plot, title)
        else:
            from papf.plots.paths import plot_paths

            label = f"{args.planner} ({result.outcome})"
            plot_paths(world, {label: result.path}, args.plot, title,
                       times={label: result.times})
    s = result.summary()
    if args.json:
        print(json.dumps(s))
    else:
        print(f"{s['world']} {s['planner']}: {s['outcome']} after {s['duration_s']:.1f} s, "
              f"{s['path_length_m']:.2f} m, min clearance {s['min_clearance_m']:.2f} m"
              + (f" ({s['reason']})" if s["reason"] else ""))
    for what, path in (("plot", args.plot), ("path", args.out)):
        if path:  # on stderr: with --json, stdout holds the one JSON object only
            print(f"{what}: {os.path.abspath(path)}", file=sys.stderr)
    return EXIT_CODES.get(result.outcome, 6)


def _fixed_step(world, args) -> int:
    """Wang's published simulation (:func:`papf.offline.wang_step.fixed_step`)."""
    from common.errors import ConfigError
    from papf.offline.wang_step import fixed_step

    methods = {"wang-apf": "traditional", "wang": "improved"}
    if args.planner not in methods:
        raise ConfigError(f"--motion fixed-step: planner {args.planner!r}; valid: {sorted(methods)}")
    r = fixed_step(world, methods[args.planner])
    if args.plot:
        from papf.plots.world import plot_paths

        plot_paths(world, {f"{args.planner} ({r.outcome})": r.path}, args.plot,
                   f"{world.name}: {args.planner}, fixed step (Wang's simulation)")
    s = r.summary()
    print(json.dumps(s) if args.json else
          f"{s['world']} {args.planner} (fixed step): {s['outcome']} after {s['iterations']} "
          f"iterations, path {s['path_length']:.2f}, min clearance {s['min_clearance']:.2f}")
    return {"reached": 0, "collision": 4}.get(r.outcome, 3)
