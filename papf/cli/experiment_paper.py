"""``papf experiment wang | horizon | deviations | test1-sweep | cases``: the paper-fidelity studies (issue 14).

``wang`` Wang's Figs. 5-12 as published and on the ROSbot (:mod:`papf.experiments.wang_figs`);
``horizon`` PAPF's lambda study of Fig. 7 and ``deviations`` each of our PAPF deviations
switched alone (:mod:`papf.experiments.paper_study`), offline; ``test1-sweep`` the APF-only
calibration of papf-test-1's box (:mod:`papf.experiments.test1_sweep`); ``cases`` the studies behind
the older planner tables (:mod:`papf.experiments.doc_cases`). Exit code 0 done, 2 usage.
"""

from __future__ import annotations

from pathlib import Path

from common.errors import ConfigError
from common.params import SEED, arg_type, integer


def preset_list(text: str) -> list[str]:
    """``"default,paper"`` -> ``["default", "paper"]``; ConfigError names the valid presets."""
    from nodes.planner.registry import PRESETS

    names = [p.strip() for p in text.split(",") if p.strip()]
    bad = [p for p in names if p not in PRESETS]
    if bad or not names:
        raise ConfigError(f"--presets {text!r}: unknown {bad}; valid: {list(PRESETS)}")
    return list(dict.fromkeys(names))


def _study(exp, name: str, summary: str, description: str, func):
    """A study's subcommand with its ``--out DIR`` (default: the study's name)."""
    parser = exp.add_parser(name, help=summary, description=description)
    parser.add_argument("--out", default=name, metavar="DIR", help="output directory")
    parser.set_defaults(func=func)
    return parser


def add_paper_studies(exp) -> None:
    """Add the paper studies (safety-floor, wang, horizon, ...) to the experiments ``exp``."""
    f = exp.add_parser("safety-floor", help="the safety parameters' floors, measured offline",
                       description="Each safety parameter (d_o, k_vo_l, q_o, k_ro_l, k_rep_l, "
                                   "rho_0, w_max) swept downwards alone on energy-blocking and papf-test-1, "
                                   "then their product at its floor; one CSV row per run, written "
                                   "as it ends (a re-run skips the runs already in the CSV).")
    f.add_argument("--out", default="safety-floor.csv", metavar="FILE.csv",
                   help="the CSV (default safety-floor.csv; docs/data/safety-floor.csv in the docs)")
    f.add_argument("--car", action="store_true",
                   help="instead: the car planner's obstacle field (obstacle_gain, a_x, a_y) on "
                        "the IAPF paper's cases A-D (docs/data/safety-floor-iapf.csv)")
    f.add_argument("--attraction", action="store_true",
                   help="instead: the attraction gains (k_vg, q_g, Wang's k_att) swept upwards, "
                        "each row with its attraction-to-repulsion ratio "
                        "(docs/data/safety-attraction.csv)")
    f.set_defaults(func=cmd_safety_floor)
    w = _study(exp, "wang", "Wang's Figs. 5-12: the published point simulation and the ROSbot",
               "Each of Wang's figures as published (a point stepping 0.5 along the force, J = 200, "
               "Table 1 gains) and with the wang-apf / wang planners offline; writes wang.md and "
               "wang.csv into --out.", cmd_wang)
    w.set_defaults(out="wang-figs")
    w.add_argument("--seed", type=arg_type("--seed", SEED), default=0, help="LiDAR noise seed (default 0)")

    h = _study(exp, "horizon", "PAPF's horizon of prediction (paper Fig. 7), offline",
               "PAPF with lambda in {0.5, 1, 1.5, 2} m (both presets) and APF on the Fig. 7-like "
               "world papf-horizon: path, duration, turning, cycle time; writes horizon.md and "
               "horizon.csv into --out.", cmd_horizon)
    h.add_argument("--seed", type=arg_type("--seed", SEED), default=0, help="LiDAR noise seed (default 0)")

    d = _study(exp, "deviations", "each PAPF deviation from the paper switched alone, offline",
               "PAPF default and paper presets, and each deviation switched on alone over the paper "
               "preset (--both: and off alone from the default), on N random worlds and PAPF Tests "
               "I-VI; writes deviations.md/.csv.", cmd_deviations)
    d.add_argument("--n", type=arg_type("--n", integer(1, 10_000)), default=3, help="random worlds (default 3: a field, a dead end, a gap)")
    d.add_argument("--both", action="store_true",
                   help="also switch each deviation off alone from the default preset")
    d.add_argument("--seed", type=arg_type("--seed", SEED), default=1, help="random world set (default 1)")

    t = _study(exp, "test1-sweep", "papf-test-1's box sized and placed by APF alone, offline",
               "APF (offline, seeds 0-2) on papf-test-1 with its box's side, distance along the "
               "start-goal line and offset to its right swept; picks the box whose mean APF path is "
               "nearest the paper's 4.50 m (Table 2); writes test1-sweep.md/.csv and "
               "test1-sweep-runs.csv into --out.", cmd_test1_sweep)
    t.add_argument("--seeds", default="0,1,2", metavar="S1,S2", help="LiDAR noise seeds (default 0,1,2)")

    c = _study(exp, "cases", "the small studies behind the older planner tables of the docs",
               "Named studies (AR-APF and Wang ablations and results, the energy world through the "
               "stack with every planner and smaller d_o): each case's runs offline and/or through "
               "the stack; writes <study>.csv (one summary row per case) and cases-runs.csv into "
               "--out.", cmd_cases)
    c.add_argument("--studies", default="all", metavar="S1,S2",
                   help="comma-separated studies, or all (default)")


def cmd_wang(args) -> int:
    """``papf experiment wang``: Wang's Figs. 5-12, point simulation and ROSbot; the exit code."""
    from papf.experiments.wang_figs import run_wang

    run_wang(args.out, args.seed)
    print((Path(args.out) / "wang.md").read_text())
    return 0


def cmd_horizon(args) -> int:
    """``papf experiment horizon``: PAPF's horizon of prediction (Fig. 7); the exit code."""
    from papf.experiments.paper_study import run_horizon

    run_horizon(args.out, args.seed)
    print((Path(args.out) / "horizon.md").read_text())
    return 0


def cmd_deviations(args) -> int:
    """``papf experiment deviations``: the deviations study (2 if ``--n`` < 1); the exit code."""
    from papf.experiments.paper_study import run_deviations

    if args.n < 1:
        raise ConfigError(f"--n {args.n}: need at least 1 world")
    run_deviations(args.out, args.n, args.seed, both=args.both)
    print((Path(args.out) / "deviations.md").read_text())
    return 0


def cmd_test1_sweep(args) -> int:
    """``papf experiment test1-sweep``: papf-test-1's box sized by APF alone; the exit code."""
    from papf.experiments.test1_sweep import run_sweep

    try:
        seeds = [int(s) for s in args.seeds.split(",") if s.strip()]
    except ValueError:
        seeds = []
    if not seeds:
        raise ConfigError(f"--seeds {args.seeds!r}: give comma-separated integers, e.g. 0,1,2")
    run_sweep(args.out, seeds=seeds)
    print((Path(args.out) / "test1-sweep.md").read_text())
    return 0


def cmd_cases(args) -> int:
    """``papf experiment cases``: the docs' case studies named by ``--studies``; the exit code."""
    from papf.experiments.doc_cases import STUDIES, run_cases

    names = list(STUDIES) if args.studies == "all" else [n.strip() for n in args.studies.split(",") if n.strip()]
    bad = [n for n in names if n not in STUDIES]
    if bad or not names:
        raise ConfigError(f"--studies {args.studies!r}: unknown {bad}; valid: {list(STUDIES)} or all")
    run_cases(args.out, names)
    print(f"wrote {', '.join(n + '.csv' for n in names)} and cases-runs.csv into {args.out}")
    return 0


def cmd_safety_floor(args) -> int:
    """``papf experiment safety-floor``: each safety parameter's floor; the exit code."""
    from papf.experiments.safety_floor import run

    if args.car and args.attraction:
        raise ConfigError("--car and --attraction are two sweeps: give one")
    from bench.csvrows import check_csv
    from papf.experiments.safety_floor import ATTRACTION_FIELDS, FIELDS

    check_csv(Path(args.out), ATTRACTION_FIELDS if args.attraction else FIELDS)   # before a run
    floors = run(Path(args.out), progress=lambda line: print(line, flush=True), car=args.car,
                 attraction=args.attraction)
    print("floors: " + ", ".join(f"{k}={v:g}" for k, v in floors.items()))
    return 0
