"""``papf experiment link``: APF and PAPF split over emulated links (:mod:`papf.experiments.link`)."""

from __future__ import annotations

import sys
from pathlib import Path

from common.errors import ConfigError
from common.params import SEED, TIMEOUT, arg_type


def add_link(exp) -> None:
    """Add ``papf experiment link`` to the experiments' subcommands ``exp``."""
    from papf.experiments.link import LINKS, SWEEP_MS, TIMEOUT_S

    p = exp.add_parser(
        "link", help="what a bad link costs: APF and PAPF split over emulated links and outages",
        description="On the energy world, each run as `papf run --link` (robot and laptop on "
                    "their own routers joined through papf link, real time): planners x link "
                    "profiles x outages (success, time, path, mAh, link figures), and a delay "
                    "sweep (the latency up to which each planner reaches its goal). Writes "
                    "link.csv, link-sweep.csv, link.md, link.png into --out; finished runs are "
                    "kept in OUT/runs/ (a re-run makes only the others). docs/link.md.")
    p.add_argument("--out", default="link", metavar="DIR", help="output directory")
    p.add_argument("--planners", default="apf,papf", help="comma-separated (default apf,papf)")
    p.add_argument("--links", default=",".join(label for label, _ in LINKS),
                   help="comma-separated subset of " + ",".join(label for label, _ in LINKS))
    p.add_argument("--outage", default="10@20", metavar="S@T|none",
                   help="the outage of the outage runs (default 10@20: 10 s, 20 s into the "
                        "drive); none: no outage runs")
    p.add_argument("--sweep", default=",".join(map(str, SWEEP_MS)), metavar="MS,MS|none",
                   help="one-way delays of the delay sweep [ms] (default "
                        f"{','.join(map(str, SWEEP_MS))}); none: no sweep")
    p.add_argument("--world", default="energy", help="world (default energy, the PAPF paper's)")
    p.add_argument("--seed", type=arg_type("--seed", SEED), default=0, help="noise seed (0)")
    p.add_argument("--timeout", type=arg_type("--timeout", TIMEOUT), default=TIMEOUT_S,
                   metavar="S", help=f"run-time limit per run (default {TIMEOUT_S:g})")
    p.add_argument("--namespace", default="linkexp",
                   help="key namespace of the runs (default linkexp: a session in rosbot is "
                        "not disturbed)")
    p.add_argument("--record", action="store_true",
                   help="record each run's laptop side to OUT/recordings/<run>.mcap")
    p.set_defaults(func=cmd_link)


def _names(text: str, valid: list[str], flag: str) -> list[str]:
    names = [n.strip() for n in text.split(",") if n.strip()]
    bad = [n for n in names if n not in valid]
    if not names or bad:
        raise ConfigError(f"{flag} {text!r}: valid names are {', '.join(valid)}")
    return names


def todo_of(args) -> list:
    """The runs ``papf experiment link``'s options ask for (ConfigError on a bad one)."""
    from nodes.planner.registry import PLANNERS
    from papf.experiments.link import LINKS, cases
    from papf.link.spec import parse_outage

    planners = _names(args.planners, list(PLANNERS), "--planners")
    labels = _names(args.links, [label for label, _ in LINKS], "--links")
    links = [(label, spec) for label, spec in LINKS if label in labels]
    outages = [("none", "")]
    if args.outage.strip().lower() != "none":
        length, start = parse_outage(args.outage)
        outages.append((f"{length:g}s@{start:g}s", f"outage={length:g}@{start:g}"))
    sweep: list[int] = []
    if args.sweep.strip().lower() != "none":
        try:
            sweep = [int(x) for x in args.sweep.split(",") if x.strip()]
        except ValueError:
            raise ConfigError(f"--sweep {args.sweep!r}: comma-separated whole milliseconds, "
                              "or none") from None
        if not sweep or any(not 0 <= ms <= 60_000 for ms in sweep):
            raise ConfigError(f"--sweep {args.sweep!r}: delays in [0, 60000] ms, or none")
    return cases(planners, links, outages, sweep)


def cmd_link(args) -> int:
    """``papf experiment link``: the runs, the tables, the plot; the exit code."""
    from papf.experiments.link import run_link_experiment  # zenoh: when run
    from papf.launch.preflight import namespace
    from worlds import load_world

    todo = todo_of(args)
    namespace(args.namespace)   # ConfigError before any run
    load_world(args.world)   # WorldError (exit 2, one line) before any run
    run_link_experiment(args.out, todo, seed=args.seed, timeout_s=args.timeout,
                        record=args.record, world=args.world, namespace=args.namespace,
                        echo=lambda line: print(line, file=sys.stderr, flush=True))
    print((Path(args.out) / "link.md").read_text())
    return 0
