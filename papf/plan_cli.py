"""``papf plan`` and ``papf experiment paper-tests | random``. Wire with ``register(subparsers)``.

``experiment_parser(subparsers)`` creates the ``experiment`` command once and returns its
sub-subparsers (cached on ``subparsers``), so other modules can add their experiments
(e.g. ``energy``) to the same command. Handlers return the exit code.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

_EXPERIMENT_ATTR = "_papf_experiment_subparsers"


def experiment_parser(subparsers):
    """The ``experiment`` command's sub-subparsers object (created on first call)."""
    existing = getattr(subparsers, _EXPERIMENT_ATTR, None)
    if existing is not None:
        return existing
    p = subparsers.add_parser("experiment", help="run an experiment (many runs, a table, plots)",
                              description="Experiments: many runs of planners on worlds, "
                                          "tabulated. `papf experiment NAME --help` for each.")
    sub = p.add_subparsers(dest="experiment", required=True, metavar="EXPERIMENT")
    setattr(subparsers, _EXPERIMENT_ATTR, sub)
    return sub


def _planner_list(text: str) -> list[str]:
    from common.errors import ConfigError
    from nodes.planner.registry import PLANNERS

    names = [p.strip() for p in text.split(",") if p.strip()]
    bad = [p for p in names if p not in PLANNERS]
    if bad or not names:
        raise ConfigError(f"--planners {text!r}: unknown {bad}; valid: {sorted(PLANNERS)}")
    return names


def register(subparsers) -> None:
    """Add ``plan`` and ``experiment paper-tests`` / ``experiment random``."""
    p = subparsers.add_parser("plan", help="run a planner on a world offline (no processes)",
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

    sub = experiment_parser(subparsers)
    e = sub.add_parser("paper-tests", help="every paper world with every planner: a Table-2 table",
                       description="Run PAPF Tests I-VI, AR-APF Tests I-III and Wang's 2-D worlds "
                                   "with each planner (through the process stack unless --offline); "
                                   "write paper-tests.md/.csv and one PNG per world into --out.")
    e.add_argument("--planners", default="apf,papf,arapf,wang", help="comma-separated")
    e.add_argument("--out", default="paper-tests", metavar="DIR", help="output directory")
    e.add_argument("--seed", type=int, default=0, help="noise seed of every run (default 0)")
    e.add_argument("--worlds", help="comma-separated subset of the paper worlds")
    e.add_argument("--timeout", type=float, default=300.0, metavar="S", help="sim-time limit per run")
    e.add_argument("--offline", action="store_true", help="offline planner runs (no processes)")
    e.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="planner setting for every planner, repeatable (e.g. a shared APF one)")
    e.set_defaults(func=cmd_paper_tests)

    r = sub.add_parser("random", help="success and collision rates on seeded random worlds",
                       description="Generate N solvable random worlds (obstacle fields, dead ends, "
                                   "narrow gaps), run every planner on each, report rates per "
                                   "planner into --out (random.md, random.csv, worlds/).")
    r.add_argument("--n", type=int, default=50, help="solvable worlds (default 50)")
    r.add_argument("--seed", type=int, default=0, help="world-set and noise seed (default 0)")
    r.add_argument("--planners", default="apf,papf,arapf,wang", help="comma-separated")
    r.add_argument("--out", default="random-worlds", metavar="DIR", help="output directory")
    r.add_argument("--timeout", type=float, default=300.0, metavar="S", help="sim-time limit per run")
    r.add_argument("--plots", action="store_true", help="one PNG per world with every path")
    r.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="planner setting for every planner, repeatable (e.g. a shared APF one)")
    mode = r.add_mutually_exclusive_group()
    mode.add_argument("--offline", dest="mode", action="store_const", const="offline",
                      help="offline planner runs (default; fast)")
    mode.add_argument("--stack", dest="mode", action="store_const", const="stack",
                      help="every run through the whole process stack (slow)")
    r.set_defaults(func=cmd_random, mode="offline")


def cmd_plan(args: argparse.Namespace) -> int:
    from papf.monitor import EXIT_CODES
    from papf.plan import plan, write_path
    from worlds import load_world

    world = load_world(args.world)
    result = plan(world, args.planner, params=args.set, seed=args.seed, max_time_s=args.timeout,
                  dt=args.dt, params_file=args.params, keep_states=bool(args.plot))
    if args.out:
        write_path(result, args.out)
    if args.plot:
        title = f"{world.name}: {args.planner} (offline, seed {args.seed})"
        if world.dims == 2:  # with the planner's mind and the robot's footprint
            from papf.mind_plots import plot_plan

            plot_plan(world, result, args.plot, title)
        else:
            from papf.plots import plot_paths

            plot_paths(world, {f"{args.planner} ({result.outcome})": result.path}, args.plot,
                       title)
    if args.json:
        print(json.dumps(result.summary()))
    else:
        s = result.summary()
        print(f"{s['world']} {s['planner']}: {s['outcome']} after {s['duration_s']:.1f} s, "
              f"{s['path_length_m']:.2f} m, min clearance {s['min_clearance_m']:.2f} m"
              + (f" ({s['reason']})" if s["reason"] else ""))
    return EXIT_CODES.get(result.outcome, 6)


def cmd_paper_tests(args: argparse.Namespace) -> int:
    from common.errors import ConfigError
    from papf.experiments.paper_tests import PAPER_WORLDS, run_paper_tests

    worlds = PAPER_WORLDS
    if args.worlds:
        worlds = tuple(w.strip() for w in args.worlds.split(",") if w.strip())
        bad = [w for w in worlds if w not in PAPER_WORLDS]
        if bad:
            raise ConfigError(f"--worlds: {bad} are not paper worlds; valid: {list(PAPER_WORLDS)}")
    run_paper_tests(args.out, _planner_list(args.planners), args.seed,
                    "offline" if args.offline else "stack", worlds, args.timeout, sets=args.set)
    print((Path(args.out) / "paper-tests.md").read_text())
    print(f"wrote {args.out}/paper-tests.md, paper-tests.csv and one PNG per world", file=sys.stderr)
    return 0


def cmd_random(args: argparse.Namespace) -> int:
    from papf.experiments.random_worlds import run_random

    run_random(args.out, args.n, args.seed, _planner_list(args.planners), args.mode, args.timeout,
               args.plots, sets=args.set)
    print((Path(args.out) / "random.md").read_text())
    print(f"wrote {args.out}/random.md, random.csv and worlds/", file=sys.stderr)
    return 0
