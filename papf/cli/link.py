"""``papf link``: a userspace link emulator between a laptop's and a robot's Zenoh routers
(:mod:`papf.link.proxy`; profiles and their sources: docs/link.md)."""

from __future__ import annotations

from common.params import SEED, arg_type
from papf.link import spec as link_spec


def _checked(parse, name: str):
    """An argparse ``type=`` from a parser that raises ConfigError (exit 2, one line)."""
    def typed(text: str):
        import argparse

        from common.errors import ConfigError

        try:
            return parse(text)
        except ConfigError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None
    typed.__name__ = name
    return typed


_outage = _checked(link_spec.parse_outage, "outage")
_spec = _checked(link_spec.parse_spec, "spec")
_profile = _checked(link_spec.profile, "profile")


def register(sub) -> None:
    """Add ``papf link`` and its options to the subcommands ``sub``."""
    p = sub.add_parser(
        "link", help="emulate a network link (delay, jitter, rate, outages) between two routers",
        description="Forward TCP from --listen to --to with a link's behaviour, both ways: "
                    "one-way delay and jitter (delivery stays in order, as TCP's), a rate "
                    "limit, losses, outages on a schedule or at random. No root, no netem. "
                    "Point the laptop's router (--join / --connect) at --listen and --to at the "
                    "robot's router. Profiles: " + ", ".join(link_spec.PROFILES) + " (sources: "
                    "docs/link.md). Ctrl-C/SIGTERM: stop and print the stats; SIGUSR1: the "
                    "outage schedule's t0 is now.")
    p.add_argument("--listen", required=True, metavar="EP",
                   help="where the laptop side connects, e.g. tcp/127.0.0.1:7448")
    p.add_argument("--to", required=True, metavar="EP",
                   help="the robot side's router, e.g. tcp/192.168.1.10:7447")
    p.add_argument("--profile", type=_profile, metavar="|".join(link_spec.PROFILES),
                   help="a link with published figures (docs/link.md); the options below "
                        "override its numbers")
    p.add_argument("--spec", type=_spec, metavar="SPEC",
                   help="PROFILE and/or key=value items, as papf run --link takes, e.g. "
                        "wifi,outage=10@20 or delay=200,jitter=150")
    p.add_argument("--delay", type=arg_type("--delay", link_spec.MS), metavar="MS",
                   help="one-way delay, each direction [ms]")
    p.add_argument("--jitter", type=arg_type("--jitter", link_spec.MS), metavar="MS",
                   help="extra one-way delay, uniform in [0, MS] [ms]")
    p.add_argument("--jitter-period", type=arg_type("--jitter-period", link_spec.JITTER_PERIOD),
                   metavar="MS", help="a jitter value holds this long (default 100 ms; 0: a new "
                                      "value per chunk)")
    p.add_argument("--rate", type=arg_type("--rate", link_spec.RATE), metavar="KBIT",
                   help="rate limit, both directions [kbit/s] (default: unlimited)")
    p.add_argument("--rate-back", type=arg_type("--rate-back", link_spec.RATE), metavar="KBIT",
                   help="rate limit of the --to -> --listen direction, if it differs [kbit/s]")
    p.add_argument("--loss", type=arg_type("--loss", link_spec.LOSS), metavar="PCT",
                   help="chunks that wait one TCP retransmission timeout [%%]")
    p.add_argument("--outage", type=_outage, action="append", default=[], metavar="S@T",
                   help="an outage of S seconds from t = T s (repeatable), e.g. 10@20")
    p.add_argument("--outage-mode", choices=link_spec.OUTAGE_MODES,
                   help="stall: connections stay, nothing passes (default); reset: every "
                        "connection is reset, new ones refused until the link is back")
    p.add_argument("--outage-rate", type=arg_type("--outage-rate", link_spec.OUTAGE_RATE),
                   metavar="N", help="random outages per minute (seeded; default 0)")
    p.add_argument("--outage-mean", type=arg_type("--outage-mean", link_spec.OUTAGE_MEAN),
                   metavar="S", help="mean length of a random outage (default 2 s)")
    p.add_argument("--seed", type=arg_type("--seed", SEED), help="seed of jitter, losses and "
                                                                 "random outages (default 0)")
    p.add_argument("--t0", choices=("start", "signal"), default="start",
                   help="when the outage schedule's clock starts: now (default) or at SIGUSR1 "
                        "(papf run --link sends it when its run starts)")
    p.add_argument("--stats", metavar="FILE", help="write the stats as JSON here at exit")
    p.add_argument("--force", action="store_true", help="replace the --stats file if it exists")
    p.set_defaults(func=cmd_link)


def spec_of(args):
    """The LinkSpec of ``papf link``'s options: --spec, else --profile, then the numbers."""
    base = args.spec or args.profile or link_spec.LinkSpec()
    return link_spec.with_overrides(
        base, outages=args.outage, delay=args.delay,
        jitter=None if args.jitter is None else link_spec.uniform(args.jitter),
        jitter_period=args.jitter_period, rate=args.rate, rate_back=args.rate_back,
        loss=args.loss, outage_mode=args.outage_mode, outage_rate=args.outage_rate,
        outage_mean=args.outage_mean, seed=args.seed)


def cmd_link(args) -> int:
    """``papf link``: forward until stopped; the exit code."""
    from papf.link.proxy import run_link  # asyncio: only when forwarding

    return run_link(spec_of(args), args.listen, args.to, args.stats, args.force,
                    t0_on_signal=args.t0 == "signal")
