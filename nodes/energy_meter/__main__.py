"""Energy meter node: ``python -m nodes.energy_meter [--model motor|paper] [--set name=value]``.

Emulates the PAPF paper's charge measurement (IV-C) from the base driver's messages
(docs/energy.md; the models and constants: docs/energy.md).

Ports: :mod:`nodes.energy_meter.ports` (``--help`` prints them).

Settings: ``--model`` (``motor`` default, or ``paper`` = eq. (6)); ``--set name=value``,
repeatable, overrides a constant of the pack (``initial_soc``, ``capacity_mAh``,
``cell_resistance_ohm``, ``cells_series``) or of the model (``p_s_W``, ``f_v_Nm``,
``regeneration=true``, ...; an unknown name lists the valid ones); the Zenoh options.
Bad payloads and messages the meter cannot use are logged, counted and dropped.

``--robots r1,r2,...``: one process meters a fleet (the launch profile's ``fleet = "one"``),
each robot with a meter of its own (the same settings) on its own namespace — its ``odom``
and ``wheels`` in, its ``battery`` out, its token ``<robot>/alive/energy_meter`` — and one
loop taking every robot's batched streams: the same figures as a meter process per robot.
"""

from __future__ import annotations

import argparse

from common.cliparse import ArgumentParser
from common.errors import ConfigError, PapfError
from common.ports import describe, plain
from common.transport import (
    Node,
    add_zenoh_args,
    exit_fast,
    fleet_names,
    open_node,
    setup_logging,
)
from nodes.energy_meter.ports import PORTS, VARIANTS

from .core import EnergyMeter
from .models import DEFAULT_MODEL, MODELS

NODE_NAME = "energy_meter"


def parse_settings(items: list[str]) -> dict[str, str]:
    """``["a=1", "b=x"]`` -> ``{"a": "1", "b": "x"}``."""
    out = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name.strip():
            raise ConfigError(f"--set {item!r}: expected name=value")
        out[name.strip()] = value.strip()
    return out


def parse_resume(text: str) -> tuple[float, float, float, int]:
    """``"1.5,20.3,0.99,123000000"`` -> (mAh, J, SoC, stamp ns); ConfigError otherwise."""
    parts = text.split(",")
    try:
        if len(parts) != 4:
            raise ValueError
        return float(parts[0]), float(parts[1]), float(parts[2]), int(parts[3])
    except ValueError:
        raise ConfigError(f"--resume {text!r}: expected MAH,J,SOC,STAMP_NS") from None


def listen(node: Node) -> None:
    """A meter's subscriptions and publisher on ``node``'s namespace. Batched: the meter
    watches two 50 Hz streams off the lockstep's path, so it takes them every 10 ms in one
    wake instead of being woken for every message."""
    node.subscribe("odom", batched=True)
    node.subscribe("wheels", batched=True)
    node.subscribe("battery/measured", batched=True)  # the robot's voltage replaces the model's
    node.declare_publishers("battery")


def open_shares(node: Node, names, log) -> dict[str, Node]:
    """The node of each meter: ``node`` itself for ``""``, else a robot's share on ``node``'s
    session (its own keys, seals, stamps and token), gathered into ``node``'s loop; ready."""
    shares = {}
    for name in names:
        share = shares[name] = node.share(name, log)
        listen(share)
    for share in shares.values():
        share.ready()
    if "" not in shares:
        node.ready()   # <namespace>/alive/energy_meter too: the process itself is up
    return shares


def meter_one(meter: EnergyMeter, topic: str, msg):
    """Feed one message; the pack state to publish, or None."""
    if topic == "battery/measured":
        meter.set_measured_voltage(msg.voltage, msg.stamp_ns)
        return None
    return meter.feed(msg)


def run(meters: dict[str, EnergyMeter], args: argparse.Namespace, log) -> None:
    """Subscribe, declare, get ready, then meter every message until stopped. ``meters``:
    ``{"": meter}`` on ``--namespace``, or one per robot of ``--robots`` (module doc)."""
    errors = 0
    with open_node(NODE_NAME, args, log) as node:
        shares = open_shares(node, meters, log)
        for topic, msg in node.messages():
            if msg is None:
                continue
            name, topic = ("", topic) if "" in meters else topic.split("/", 1)
            try:
                state = meter_one(meters[name], topic, msg)
            except PapfError as exc:   # e.g. a measured voltage <= 0: counted, dropped
                errors += 1
                if errors <= 5 or errors % 100 == 0:
                    log.warning("dropped message #%d it cannot meter: %s", errors, exc)
                continue
            if state is not None:
                shares[name].publish("battery", state)
        for name, meter in meters.items():
            b = meter.battery
            log.info("%sstopped: %.3f mAh, %.1f J, SoC %.4f (%s model; %d stale, %d unpaired, "
                     "%d overloads)", f"{name}: " if name else "", b.charge_used_mAh, b.energy_J,
                     b.soc, meter.model_name, meter.stale, meter.discarded, b.overloads)
        for share in shares.values():
            if share is not node:
                share.close()


def main(argv: list[str] | None = None) -> int:
    parser = ArgumentParser(prog="python -m nodes.energy_meter",
                                     description=plain(__doc__.splitlines()[0]),
                                     formatter_class=argparse.RawDescriptionHelpFormatter,
                                     epilog=describe(PORTS, VARIANTS))
    parser.add_argument("--model", choices=sorted(MODELS), default=DEFAULT_MODEL,
                        help="power model: motor (DC motors, default) or paper (eq. 6)")
    parser.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                        help="override a pack or model constant (repeatable)")
    parser.add_argument("--resume", metavar="MAH,J,SOC,STAMP_NS",
                        help="go on with a run's account (a laptop that came back: papf launch "
                             "laptop --resume gives it)")
    parser.add_argument("--robots", metavar="R1,R2,...",
                        help="one process meters these robots, each on its own namespace")
    parser.add_argument("--log-level", default="INFO")
    add_zenoh_args(parser)
    args = parser.parse_args(argv)
    log = setup_logging(NODE_NAME, args.log_level)
    try:
        names = robot_names(args)
        meters = {n: EnergyMeter(args.model, parse_settings(args.set)) for n in names}
        if args.resume:
            meters[""].resume(*parse_resume(args.resume))
        run(meters, args, log)
    except ConfigError as exc:
        parser.error(str(exc))
    return 0


def robot_names(args: argparse.Namespace) -> list[str]:
    """``--robots`` as namespaces (``[""]``: this one, ``--namespace``); ConfigError for a
    name that is no plain key, a repeated one, or with ``--resume`` (one robot's account)."""
    names = fleet_names(args.robots)
    if args.resume and args.robots is not None:
        raise ConfigError("--resume goes on with one robot's account: not with --robots")
    return names


if __name__ == "__main__":
    exit_fast(main())   # the session is closed: skip the interpreter's slow teardown
