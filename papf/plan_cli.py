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


def preset_list(text: str) -> list[str]:
    """``default,paper`` -> ["default", "paper"]; ConfigError names the valid presets."""
    from common.errors import ConfigError
    from nodes.planner.registry import PRESETS

    names = [p.strip() for p in text.split(",") if p.strip()]
    bad = [p for p in names if p not in PRESETS]
    if bad or not names:
        raise ConfigError(f"--presets {text!r}: unknown {bad}; valid: {list(PRESETS)}")
    return list(dict.fromkeys(names))


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
    p.add_argument("--preset", choices=("default", "paper"), default="default",
                   help="planner preset: default (our improvements) or paper (the paper literally)")
    p.add_argument("--motion", choices=("robot", "fixed-step"), default="robot",
                   help="robot (default) or fixed-step: Wang's MATLAB point, step 0.5, J = 200, "
                        "the obstacles' centres known (planners wang-apf and wang only)")
    p.add_argument("--plot", metavar="OUT.png", help="write a PNG of the world and the path")
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
    e.add_argument("--presets", default="default", metavar="P1,P2",
                   help="planner presets side by side: default, paper or default,paper "
                        "(a planner whose paper preset changes nothing runs once)")
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
    r.add_argument("--presets", default="default", metavar="P1,P2",
                   help="planner presets side by side: default, paper or default,paper "
                        "(a planner whose paper preset changes nothing runs once)")
    mode = r.add_mutually_exclusive_group()
    mode.add_argument("--offline", dest="mode", action="store_const", const="offline",
                      help="offline planner runs (default; fast)")
    mode.add_argument("--stack", dest="mode", action="store_const", const="stack",
                      help="every run through the whole process stack (slow)")
    r.set_defaults(func=cmd_random, mode="offline")

    w = sub.add_parser("wang", help="Wang's Figs. 5-12: the published point simulation and the ROSbot",
                       description="Each of Wang's figures as published (a point stepping 0.5 along "
                                   "the force, J = 200, Table 1 gains) and with the wang-apf / wang "
                                   "planners offline; writes wang.md and wang.csv into --out.")
    w.add_argument("--out", default="wang-figs", metavar="DIR", help="output directory")
    w.add_argument("--seed", type=int, default=0, help="LiDAR noise seed (default 0)")
    w.set_defaults(func=cmd_wang)

    h = sub.add_parser("horizon", help="PAPF's horizon of prediction (paper Fig. 7), offline",
                       description="PAPF with lambda in {0.5, 1, 1.5, 2} m (both presets) and APF on "
                                   "the Fig. 7-like world papf-horizon: path, duration, turning, cycle "
                                   "time; writes horizon.md and horizon.csv into --out.")
    h.add_argument("--out", default="horizon", metavar="DIR", help="output directory")
    h.add_argument("--seed", type=int, default=0, help="LiDAR noise seed (default 0)")
    h.set_defaults(func=cmd_horizon)

    d = sub.add_parser("deviations", help="each PAPF deviation from the paper switched alone, offline",
                       description="PAPF default and paper presets, and each deviation switched on "
                                   "alone over the paper preset and off alone from the default, on N "
                                   "random worlds and the paper worlds; writes deviations.md/.csv.")
    d.add_argument("--out", default="deviations", metavar="DIR", help="output directory")
    d.add_argument("--n", type=int, default=20, help="random worlds (default 20)")
    d.add_argument("--seed", type=int, default=1, help="random world set (default 1)")
    d.set_defaults(func=cmd_deviations)


def cmd_plan(args: argparse.Namespace) -> int:
    from nodes.planner.registry import preset_sets
    from papf.monitor import EXIT_CODES
    from papf.plan import plan, write_path
    from worlds import load_world

    world = load_world(args.world)
    if args.motion == "fixed-step":
        return _fixed_step(world, args)
    result = plan(world, args.planner, params=[*preset_sets(args.preset), *args.set],
                  seed=args.seed, max_time_s=args.timeout,
                  dt=args.dt, params_file=args.params)
    if args.out:
        write_path(result, args.out)
    if args.plot:
        from papf.plots import plot_paths

        plot_paths(world, {f"{args.planner} ({result.outcome})": result.path}, args.plot,
                   f"{world.name}: {args.planner} (offline, seed {args.seed})")
    if args.json:
        print(json.dumps(result.summary()))
    else:
        s = result.summary()
        print(f"{s['world']} {s['planner']}: {s['outcome']} after {s['duration_s']:.1f} s, "
              f"{s['path_length_m']:.2f} m, min clearance {s['min_clearance_m']:.2f} m"
              + (f" ({s['reason']})" if s["reason"] else ""))
    return EXIT_CODES.get(result.outcome, 6)


def _fixed_step(world, args) -> int:
    from common.errors import ConfigError
    from papf.pointsim import fixed_step

    methods = {"wang-apf": "traditional", "wang": "improved"}
    if args.planner not in methods:
        raise ConfigError(f"--motion fixed-step: planner {args.planner!r}; valid: {sorted(methods)}")
    r = fixed_step(world, methods[args.planner])
    if args.plot:
        from papf.plots import plot_paths

        plot_paths(world, {f"{args.planner} ({r.outcome})": r.path}, args.plot,
                   f"{world.name}: {args.planner}, fixed step (Wang's simulation)")
    s = r.summary()
    print(json.dumps(s) if args.json else
          f"{s['world']} {args.planner} (fixed step): {s['outcome']} after {s['iterations']} "
          f"iterations, path {s['path_length']:.2f}, min clearance {s['min_clearance']:.2f}")
    return {"reached": 0, "collision": 4}.get(r.outcome, 3)


def cmd_wang(args: argparse.Namespace) -> int:
    from papf.experiments.wang_figs import run_wang

    run_wang(args.out, args.seed)
    print((Path(args.out) / "wang.md").read_text())
    return 0


def cmd_horizon(args: argparse.Namespace) -> int:
    from papf.experiments.paper_study import run_horizon

    run_horizon(args.out, args.seed)
    print((Path(args.out) / "horizon.md").read_text())
    return 0


def cmd_deviations(args: argparse.Namespace) -> int:
    from common.errors import ConfigError
    from papf.experiments.paper_study import run_deviations

    if args.n < 1:
        raise ConfigError(f"--n {args.n}: need at least 1 world")
    run_deviations(args.out, args.n, args.seed)
    print((Path(args.out) / "deviations.md").read_text())
    return 0


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
                    "offline" if args.offline else "stack", worlds, args.timeout, sets=args.set,
                    presets=preset_list(args.presets))
    print((Path(args.out) / "paper-tests.md").read_text())
    print(f"wrote {args.out}/paper-tests.md, paper-tests.csv and one PNG per world", file=sys.stderr)
    return 0


def cmd_random(args: argparse.Namespace) -> int:
    from papf.experiments.random_worlds import run_random

    run_random(args.out, args.n, args.seed, _planner_list(args.planners), args.mode, args.timeout,
               args.plots, sets=args.set, presets=preset_list(args.presets))
    print((Path(args.out) / "random.md").read_text())
    print(f"wrote {args.out}/random.md, random.csv and worlds/", file=sys.stderr)
    return 0
