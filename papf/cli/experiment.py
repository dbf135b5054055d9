"""``papf experiment energy | paper-tests | random | iapf | traffic | crowd``: many runs, a table, plots.

``energy`` is the PAPF paper's energy experiment (IV-C) through the process stack,
recorded (:mod:`papf.experiments.energy`); ``paper-tests`` every paper world with every
planner (:mod:`papf.experiments.paper_tests`); ``random`` success and collision rates on
seeded random worlds (:mod:`papf.experiments.random_worlds`). Exit code 0 done, 2 usage,
6 an energy run failed or its report disagrees with the live figures.
"""

from __future__ import annotations

import sys
from pathlib import Path

from common.errors import ConfigError
from common.params import PORT, SEED, TIMEOUT, arg_type, integer
from nodes.energy_meter.models import DEFAULT_MODEL, MODELS
from nodes.planner.registry import PLANNERS, car_variants, declared, with_role
from papf.cli.experiment_link import add_link
from papf.cli.experiment_paper import add_paper_studies, preset_list
from papf.cli.options import add_port_range, use_ports
from papf.experiments.energy import PAPER_PAIR, TIMEOUT_S, WORLD
from papf.experiments.paper_tests import PAPER_WORLDS
from papf.experiments.sweep import MAX_WORKERS


def register(sub) -> None:
    """Add ``papf experiment`` and each experiment's subcommand to ``sub``."""
    p = sub.add_parser("experiment", help="run an experiment (many runs, a table, plots)",
                       description="Experiments: many runs of planners on worlds, "
                                   "tabulated. `papf experiment NAME --help` for each.")
    exp = p.add_subparsers(dest="experiment", required=True, metavar="EXPERIMENT")
    _add_energy(exp)
    _add_paper_tests(exp)
    _add_random(exp)
    _add_iapf(exp)
    _add_traffic(exp)
    _add_crowd(exp)
    add_paper_studies(exp)
    add_link(exp)
    for name, parser in exp.choices.items():   # every experiment that writes into --out DIR
        if name != "safety-floor":
            parser.set_defaults(func=_out_dir_checked(parser.get_default("func")))


def _out_dir_checked(func):
    """``func`` after a check of ``--out DIR``: a directory, or nothing yet, whose parent
    exists (ConfigError, exit 2, before any run: a file there was a traceback after them)."""
    def checked(args):
        use_ports(args, experiment=True)   # a bad --port/--port-range: before any run
        out = Path(args.out)
        if out.exists() and not out.is_dir():
            raise ConfigError(f"--out {str(out)!r} is a file; an experiment writes into a "
                              "directory (give a new name or an existing directory)")
        if not out.exists() and not out.absolute().parent.is_dir():
            raise ConfigError(f"--out {str(out)!r}: directory {str(out.absolute().parent)!r} "
                              "does not exist")
        return func(args)
    checked.__name__ = getattr(func, "__name__", "experiment")
    return checked


def _add_energy(exp) -> None:
    p = exp.add_parser(
        "energy", help="the PAPF paper's energy experiment (IV-C): planners x runs, recorded",
        description="World 'energy'; every planner x --runs, run k with seed S+k, each recorded "
                    "to OUT/<planner>-<k>.mcap through the whole process stack; then the "
                    "report in OUT.")
    p.add_argument("--runs", type=arg_type("--runs", integer(1, 10_000)), default=3, help="runs per planner (default 3)")
    p.add_argument("--planners", default=",".join(PAPER_PAIR),
                   help=f"comma-separated (default {','.join(PAPER_PAIR)})")
    p.add_argument("--out", default="energy-experiment", metavar="DIR",
                   help="directory for the recordings and the report (default energy-experiment)")
    p.add_argument("--seed", type=arg_type("--seed", SEED), default=0,
                   help="base seed S: runs are numbered 1..N and run k uses S+k (default 0); kept "
                        "1-based so the committed figures of docs/data reproduce seed for seed")
    p.add_argument("--world", default=WORLD, help=f"world (default {WORLD})")
    p.add_argument("--timeout", type=arg_type("--timeout", TIMEOUT), default=TIMEOUT_S, metavar="S",
                   help=f"sim-time limit per run [s] (default {TIMEOUT_S:g})")
    p.add_argument("--energy-model", choices=sorted(MODELS), default=DEFAULT_MODEL,
                   help=f"the live meter's model (default {DEFAULT_MODEL})")
    p.add_argument("--worlds", metavar="W1,W2",
                   help="several worlds, each into DIR/world-<name>/, plus DIR/energy-worlds.md/.csv "
                        "(e.g. energy,energy-blocking,energy-empty)")
    _add_presets(p)
    _add_sweep(p)
    p.set_defaults(func=cmd_energy)


def _add_presets(p) -> None:
    p.add_argument("--presets", default="default", metavar="P1,P2",
                   help="planner presets side by side: default, paper or default,paper "
                        "(a planner whose paper preset changes nothing runs once)")


def _add_sweep(p) -> None:
    g = p.add_argument_group("sweep (docs/sweeps.md)")
    g.add_argument("--workers", type=arg_type("--workers", integer(1, MAX_WORKERS)), default=1, metavar="N",
                   help="runs at once on a local Dask cluster of N worker processes "
                        "(default 1: one after the other, no Dask)")
    g.add_argument("--scheduler", metavar="tcp://HOST:8786",
                   help="run on an existing Dask cluster; results are gathered here")
    g = p.add_argument_group("ports (docs/robot.md \"Ports and firewalls\")")
    g.add_argument("--port", type=arg_type("--port", PORT), metavar="PORT",
                   help="every run's router on this port, one run at a time (default: a free "
                        "port per run)")
    add_port_range(g)


def sweep_options(args):
    """The sweep options of ``--workers`` / ``--scheduler`` (ConfigError on a bad value)."""
    from papf.experiments.sweep import SweepOptions

    opts = SweepOptions(workers=args.workers, scheduler=args.scheduler)
    opts.validate()
    return opts


def _add_common(p, default_out: str) -> None:
    p.add_argument("--planners", default=",".join(with_role("compared")), help="comma-separated")
    p.add_argument("--out", default=default_out, metavar="DIR", help="output directory")
    p.add_argument("--seed", type=arg_type("--seed", SEED), default=0, help="noise (and world-set) seed (default 0)")
    p.add_argument("--timeout", type=arg_type("--timeout", TIMEOUT), default=300.0, metavar="S", help="sim-time limit per run")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="planner setting for every planner, repeatable (e.g. a shared APF one)")
    _add_presets(p)
    _add_sweep(p)


def _add_paper_tests(exp) -> None:
    p = exp.add_parser("paper-tests", help="every paper world with every planner: a Table-2 table",
                       description="Run PAPF Tests I-VI, AR-APF Tests I-III and Wang's 2-D worlds "
                                   "with each planner (through the process stack unless --offline); "
                                   "write paper-tests.md/.csv and one PNG per world into --out.")
    _add_common(p, "paper-tests")
    p.add_argument("--worlds", help="comma-separated subset of the paper worlds")
    p.add_argument("--offline", action="store_true", help="offline planner runs (no processes)")
    p.set_defaults(func=cmd_paper_tests)


def _add_random(exp) -> None:
    p = exp.add_parser("random", help="success and collision rates on seeded random worlds",
                       description="Generate N solvable random worlds (obstacle fields, dead ends, "
                                   "narrow gaps), run every planner on each, report rates per "
                                   "planner into --out (random.md, random.csv, worlds/).")
    p.add_argument("--n", type=arg_type("--n", integer(1, 10_000)), default=50, help="solvable worlds (default 50)")
    _add_common(p, "random-worlds")
    p.add_argument("--plots", action="store_true", help="one PNG per world with every path")
    mode = p.add_mutually_exclusive_group()
    mode.add_argument("--offline", dest="mode", action="store_const", const="offline",
                      help="offline planner runs (default; fast)")
    mode.add_argument("--stack", dest="mode", action="store_const", const="stack",
                      help="every run through the whole process stack (slow)")
    p.set_defaults(func=cmd_random, mode="offline")


def _add_crowd(exp) -> None:
    from nodes.planner.registry import with_role

    crowd = ",".join(with_role("crowd"))
    p = exp.add_parser("crowd", help="planners x scenes x seeds among people: the social-"
                                     "navigation measures with confidence intervals",
                       description="A robot crosses a hall among people, offline: every planner "
                                   "x scene (hall: walkers who step aside, --people of them; "
                                   "groups: standing groups and people, a walking pair; replay: "
                                   "recorded tracks replayed blind to the robot) x --runs seeds; "
                                   "crowd.md, crowd.csv, crowd-summary.csv, crowd.png, "
                                   "crowd-scenes.png and the scenes' worlds/ into --out "
                                   "(docs/experiments.md, Crowd).")
    p.add_argument("--planners", default=crowd, help=f"comma-separated (default {crowd})")
    p.add_argument("--scenes", default="hall,groups,replay", metavar="S1,S2",
                   help="comma-separated, of hall, groups, replay (default all three)")
    p.add_argument("--replay", metavar="F1,F2",
                   help="the replay scene's track files (eth-ucy: 'frame id x y' rows, e.g. "
                        "the ETH/UCY recordings; default the packaged walkers-hall.txt)")
    p.add_argument("--people", default="10", metavar="N1,N2",
                   help="the hall's numbers of people, comma-separated, each 0-20 (default 10)")
    p.add_argument("--runs", type=arg_type("--runs", integer(1, 10_000)), default=10, help="seeds per planner and scene (default 10)")
    p.add_argument("--seed", type=arg_type("--seed", SEED), default=0, help="first seed S: runs use S..S+runs-1")
    p.add_argument("--out", default="crowd", metavar="DIR", help="output directory")
    p.add_argument("--timeout", type=arg_type("--timeout", TIMEOUT), default=300.0, metavar="S",
                   help="sim-time limit per run (default 300)")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="planner setting for every planner, repeatable")
    p.add_argument("--worlds", metavar="W1,W2",
                   help="instead of the hall: these worlds as they are (e.g. the packaged "
                        "crowd-*), a row per robot -> DIR/crowd-worlds.md, .csv, -summary.csv")
    p.add_argument("--compare-models", action="store_true",
                   help="instead: ORCA against the social-force model on small scenes and "
                        "their cost per step -> DIR/crowd-models.csv")
    _add_sweep(p)
    p.set_defaults(func=cmd_crowd)


def cmd_crowd(args) -> int:
    from papf.experiments.crowd import MAX_HALL_PEOPLE, run_crowd  # pybullet: when run

    if args.compare_models:
        from papf.experiments.crowd_models import compare_models
        from papf.experiments.trials import markdown_table, write_csv

        rows = compare_models()
        write_csv(rows, Path(args.out) / "crowd-models.csv")
        print(markdown_table(list(rows[0]), [list(r.values()) for r in rows]))
        print(f"wrote {args.out}/crowd-models.csv", file=sys.stderr)
        return 0
    try:
        people = [int(v) for v in args.people.split(",") if v.strip()]
    except ValueError:
        people = []
    if not people or any(not 0 <= n <= MAX_HALL_PEOPLE for n in people):
        raise ConfigError(f"--people {args.people!r}: comma-separated whole numbers 0-"
                          f"{MAX_HALL_PEOPLE}, e.g. 0,5,10,20")
    if args.runs < 1 or args.seed < 0:
        raise ConfigError(f"--runs {args.runs} --seed {args.seed}: need runs >= 1, seed >= 0")
    if not args.timeout > 0:
        raise ConfigError(f"--timeout {args.timeout!r}: need a number of seconds > 0")
    scenes, replay = _crowd_scenes(args)
    worlds = [w.strip() for w in (args.worlds or "").split(",") if w.strip()]
    if worlds:
        from worlds import load_world

        for w in worlds:                   # a bad one: exit 2 before any run
            if load_world(w).dims != 2 or load_world(w).vehicle != "rosbot":
                raise ConfigError(f"--worlds: {w!r} is not a 2-D world of ROSbots")
    run_crowd(args.out, planner_list(args.planners), people,
              list(range(args.seed, args.seed + args.runs)), args.timeout, args.set,
              sweep_options(args), worlds=worlds, scenes=scenes, replay=replay)
    stem = "crowd-worlds" if worlds else "crowd"
    print((Path(args.out) / f"{stem}.md").read_text())
    print(f"wrote {args.out}/{stem}.md, {stem}.csv, {stem}-summary.csv"
          + ("" if worlds else ", crowd.png, crowd-scenes.png and worlds/"), file=sys.stderr)
    return 0


def _crowd_scenes(args) -> tuple[list[str], list[str]]:
    """``--scenes`` and ``--replay`` checked (every track file read) before any run."""
    from papf.experiments.crowd import SCENES

    scenes = [s.strip() for s in args.scenes.split(",") if s.strip()]
    bad = [s for s in scenes if s not in SCENES]
    if not scenes or bad:
        raise ConfigError(f"--scenes {args.scenes!r}: comma-separated, of {', '.join(SCENES)}")
    replay = [f.strip() for f in (args.replay or "").split(",") if f.strip()]
    if replay and "replay" not in scenes:
        raise ConfigError("--replay names track files for the replay scene; add replay to "
                          "--scenes")
    from papf.experiments.crowd_scenes import replay_scene

    for f in replay:                      # a bad file: exit 2, one line, before any run
        replay_scene(f, 0)
    return scenes, replay


def _add_iapf(exp) -> None:
    p = exp.add_parser("iapf", help="the IAPF paper's cases A-D at car scale: a Table-2 table, figures",
                       description="Cases A-D (worlds iapf-case-a ... d) for the paper's case times "
                                   "with IAPF, IAPF without prediction and the traditional APF, in "
                                   "the paper's vehicle model (0.02 s steps); write iapf.md, "
                                   "iapf.csv, one CSV per run and one PNG per case into --out.")
    p.add_argument("--out", default="iapf-cases", metavar="DIR", help="output directory")
    p.add_argument("--planners", default=",".join(car_variants()),
                   help=f"comma-separated: {', '.join(car_variants())} (default all)")
    p.add_argument("--cases", default="a,b,c,d", help="comma-separated subset of a,b,c,d")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="IAPF setting for every run, repeatable (e.g. --set t_c=0.4)")
    p.add_argument("--no-horizon", action="store_true",
                   help="skip timing the T = 5 s trajectory plans (faster)")
    p.add_argument("--readings", action="store_true",
                   help="instead: every case with each of our readings switched back to the "
                        "paper (readings.md, readings.csv)")
    p.set_defaults(func=cmd_iapf)


def cmd_iapf(args) -> int:
    """``papf experiment iapf``: the IAPF paper's cases at car scale; the exit code."""
    from papf.experiments.iapf import CASES, run_iapf_experiment  # matplotlib: when run
    from papf.offline.road import CAR_PLANNERS

    planners = [p.strip() for p in args.planners.split(",") if p.strip()]
    bad = [p for p in planners if p not in CAR_PLANNERS]
    cases = [f"iapf-case-{c.strip()}" for c in args.cases.split(",") if c.strip()]
    bad_cases = [c for c in cases if c not in CASES]
    if bad or not planners:
        raise ConfigError(f"--planners {args.planners!r}: unknown {bad}; valid: {sorted(CAR_PLANNERS)}")
    if bad_cases or not cases:
        raise ConfigError(f"--cases {args.cases!r}: valid: a, b, c, d")
    if args.readings:
        from papf.experiments.iapf_readings import run_readings

        run_readings(args.out, progress=lambda m: print(m, file=sys.stderr))
        print((Path(args.out) / "readings.md").read_text())
        return 0
    run_iapf_experiment(args.out, planners, cases, args.set, horizon=not args.no_horizon,
                        progress=lambda m: print(m, file=sys.stderr))
    print((Path(args.out) / "iapf.md").read_text())
    print(f"wrote {args.out}/iapf.md, iapf.csv, per-run CSVs and one PNG per case", file=sys.stderr)


def _add_traffic(exp) -> None:
    p = exp.add_parser("traffic", help="IAPF (truth and tracker tracks), APF, PAPF, AR-APF on "
                                       "the road-* worlds, through the stack",
                       description="Every road-* world with IAPF (--objects truth and tracker) "
                                   "and APF, PAPF, AR-APF, each run recorded; writes traffic.md "
                                   "and traffic.csv (outcome, collisions, left_road, lane "
                                   "changes, speeds) into --out.")
    p.add_argument("--out", default="traffic", metavar="DIR", help="output directory")
    p.add_argument("--seed", type=arg_type("--seed", SEED), default=0, help="noise seed (default 0)")
    p.add_argument("--timeout", type=arg_type("--timeout", TIMEOUT), default=150.0, metavar="S",
                   help="sim-time limit per run (default 150)")
    p.add_argument("--worlds", help="comma-separated subset of the road-* worlds")
    p.add_argument("--seeds", help="comma-separated seeds, each a full round (instead of --seed)")
    p.add_argument("--planners", help="comma-separated subset of "
                   f"{','.join([*declared('uses_objects'), *with_role('traffic')])} (default all)")
    p.set_defaults(func=cmd_traffic)


def cmd_traffic(args) -> int:
    """``papf experiment traffic``: planners among moving cars; the exit code."""
    from papf.experiments.traffic import CASES, ROAD_WORLDS, run_traffic  # zenoh, mcap: when run

    cases = CASES
    if args.planners:
        names = [p.strip() for p in args.planners.split(",") if p.strip()]
        valid = sorted({p for p, _ in CASES})
        if not names or any(p not in valid for p in names):
            raise ConfigError(f"--planners {args.planners!r}: valid names are {valid}")
        cases = tuple(c for c in CASES if c[0] in names)
    seeds = None
    if args.seeds:
        try:
            seeds = tuple(int(x) for x in args.seeds.split(",") if x.strip())
        except ValueError:
            raise ConfigError(f"--seeds {args.seeds!r}: comma-separated integers") from None
        if not seeds:
            raise ConfigError(f"--seeds {args.seeds!r}: comma-separated integers")
    worlds = ROAD_WORLDS
    if args.worlds:
        worlds = tuple(w.strip() for w in args.worlds.split(",") if w.strip())
        bad = [w for w in worlds if w not in ROAD_WORLDS]
        if bad:
            raise ConfigError(f"--worlds: {bad} are not road worlds; valid: {list(ROAD_WORLDS)}")
    run_traffic(args.out, worlds, cases, seed=args.seed, timeout_s=args.timeout,
                echo=lambda line: print(line, file=sys.stderr, flush=True), seeds=seeds)
    print((Path(args.out) / "traffic.md").read_text())
    return 0


def planner_list(text: str) -> list[str]:
    """``"a,b"`` (planner names) -> ``["a", "b"]``; ConfigError names the unknown ones."""
    names = [p.strip() for p in text.split(",") if p.strip()]
    bad = [p for p in names if p not in PLANNERS]
    if bad or not names:
        raise ConfigError(f"--planners {text!r}: unknown {bad}; valid: {sorted(PLANNERS)}")
    return names


def cmd_energy(args) -> int:
    """``papf experiment energy``: the PAPF paper's energy experiment (IV-C); the exit code."""
    from papf.experiments.energy import EnergyExperiment, print_summary, run_experiment

    planners = tuple(p.strip() for p in args.planners.split(",") if p.strip())
    exp = EnergyExperiment(out=Path(args.out), runs=args.runs, planners=planners, seed=args.seed,
                           world=args.world, timeout_s=args.timeout,
                           energy_model=args.energy_model,
                           sweep=sweep_options(args),
                           presets=tuple(preset_list(args.presets)))  # validated by run_experiment
    if args.worlds:
        from papf.experiments.energy_worlds import run_energy_worlds

        results = run_energy_worlds(exp, [w.strip() for w in args.worlds.split(",") if w.strip()])
        for r in results:
            print_summary(r)
        print((Path(args.out) / "energy-worlds.md").read_text())
        return max(r.exit_code for r in results)
    result = run_experiment(exp)
    print_summary(result)
    return result.exit_code


def cmd_paper_tests(args) -> int:
    """``papf experiment paper-tests``: every paper world with every planner; the exit code."""
    from papf.experiments.paper_tests import run_paper_tests  # pybullet, matplotlib: when run

    worlds = PAPER_WORLDS
    if args.worlds:
        worlds = tuple(w.strip() for w in args.worlds.split(",") if w.strip())
        bad = [w for w in worlds if w not in PAPER_WORLDS]
        if bad:
            raise ConfigError(f"--worlds: {bad} are not paper worlds; valid: {list(PAPER_WORLDS)}")
    run_paper_tests(args.out, planner_list(args.planners), args.seed,
                    "offline" if args.offline else "stack", worlds, args.timeout, sets=args.set,
                    sweep=sweep_options(args), presets=preset_list(args.presets))
    print((Path(args.out) / "paper-tests.md").read_text())
    print(f"wrote {args.out}/paper-tests.md, paper-tests.csv and one PNG per world", file=sys.stderr)
    return 0


def cmd_random(args) -> int:
    """``papf experiment random``: success and collision rates on random worlds; the exit code."""
    from papf.experiments.random_worlds import run_random  # pybullet, matplotlib: when run

    run_random(args.out, args.n, args.seed, planner_list(args.planners), args.mode, args.timeout,
               args.plots, sets=args.set, sweep=sweep_options(args),
               presets=preset_list(args.presets))
    print((Path(args.out) / "random.md").read_text())
    print(f"wrote {args.out}/random.md, random.csv and worlds/", file=sys.stderr)
    return 0
