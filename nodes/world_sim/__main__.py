"""The world simulator: ``python -m nodes.world_sim --world W --seed N ...``.

The simulated ROSbots, their physics, the people, the sim clock and collisions
(:mod:`nodes.world_sim.core`), on the lockstep protocol of docs/architecture.md. On the bus
it stands where the robot's base driver stands (liveliness ``<ns>/alive/base_driver``, its
keys), so every other node sees a simulated run as a real one;
``python -m nodes.base_driver --driver sim`` runs this.

Ports: :mod:`nodes.world_sim.ports` (``--help`` prints them).

Settings: ``--world`` (packaged name or .toml path), ``--seed`` (noise), ``--odom-hz``
(50; a fleet's without people: the scan rate), ``--scan-hz`` (10, lockstep instants),
``--watchdog`` (0.5 s of sim time),
``--lockstep-timeout`` (2.0 wall s, then a ``node_fault`` event and free running in
real time until a command answers the latest scan again), ``--realtime`` (pace sim
time to the wall clock, never wait for commands), plus the Zenoh options.
Liveliness token: ``<ns>/alive/base_driver``.
"""

from __future__ import annotations

import argparse
import queue
import sys
import time

from common.cliparse import ArgumentParser
from common.drive import add_driver_args
from common.errors import PapfError
from common.ports import describe, plain
from common.transport import Node, add_zenoh_args, exit_fast, open_node, setup_logging
from nodes.world_sim.loop import WorldLoop
from nodes.world_sim.ports import PORTS, VARIANTS
from schemas import Keys
from worlds import load_world

NAME = "base_driver"   # the liveliness token and log name: the driver's place on the bus
PUBLISHES = ("sim/pose", "odom", "wheels", "events")
ON_DEMAND = ("clock",)   # 50 Hz that no node of a sim run reads (sim/pose carries the time)


def drive(node: Node, loop: WorldLoop, publish=None) -> None:
    """Wire a :class:`WorldLoop` to the bus until the run ends or the node is stopped."""
    inbox, publish = node.inbox, publish or node.publish
    while not node.stop:
        out, until = loop.step(time.monotonic())
        for topic, msg in out:
            publish(topic, msg)
        if until is None:
            return
        while not (node.stop or loop.ready):   # feed inputs until `until` (past: what is queued)
            remaining = until - time.monotonic()
            try:
                item = inbox.get(timeout=min(remaining, 0.1)) if remaining > 0 else inbox.get_nowait()
            except queue.Empty:
                if remaining > 0:
                    continue
                break
            loop.on_message(*item)


def wait_for_start(node: Node) -> bool:
    """Block until an ``events`` ``run_started`` arrives (True) or stop is requested (False)."""
    while not node.stop:
        try:
            topic, msg = node.inbox.get(timeout=0.1)
        except queue.Empty:
            continue
        if topic is not None and topic.endswith("events") and msg.kind == "run_started":
            return True
    return False


def run(args: argparse.Namespace) -> int:
    from nodes.world_sim.core import WorldConfig, WorldCore, odom_rate  # pybullet: when simulating

    log = setup_logging(NAME, args.log_level)
    world = load_world(args.world)
    config = WorldConfig.from_rates(odom_rate(world, args.odom_hz, args.scan_hz), args.scan_hz,
                                    args.watchdog)
    with open_node(NAME, args, log) as node:
        publish = node.publish
        people = ("sim/people",) if world.has_people else ()   # on this node's namespace
        if world.robots:   # a fleet: each robot's share under its own namespace
            publish = fleet_nodes(node, [r.name for r in world.robots], log)
            node.declare_publishers(*people)
            node.ready()   # <namespace>/alive/base_driver too: the process itself is up
        else:
            node.subscribe("events")
            node.subscribe("cmd_vel")
            node.declare_publishers(*PUBLISHES, *people, *(("sim/bodies",) if people else ()),
                                    on_demand=ON_DEMAND)
            node.ready()
        log.info("waiting for run_started on %s (a launcher sends it; alone: papf goal X Y "
                 "--start-run, or papf teleop --start-run with --realtime)", node.keys.events)
        while wait_for_start(node):  # one run per run_started; run_ended waits for the next
            with WorldCore(world, args.seed, config) as core:
                log.info("run started: world %s, seed %d, %s", world.name, args.seed,
                         "realtime" if args.realtime else "lockstep")
                drive(node, WorldLoop(core, args.realtime, args.lockstep_timeout,
                                      time.monotonic(), log), publish)
                log.info("run stopped at sim t = %.3f s; collisions: %d", core.t_ns / 1e9,
                         core.collision_count)
        for share in getattr(node, "shares", ()):
            share.close()
    return 0


def fleet_nodes(node: Node, names: list[str], log):
    """One :class:`Node` per robot on ``node``'s session, its inputs queued to ``node``'s
    inbox as ``<name>/<topic>``, its liveliness token ``<name>/alive/base_driver``; returns
    ``publish(topic, msg)`` for the core's ``<name>/<suffix>`` topics."""
    robots = {}
    for name in names:
        share = Node(NAME, node.session, Keys(name), log)
        for topic in ("events", "cmd_vel"):
            share.subscribe(topic, handler=lambda m, t=f"{name}/{topic}": node.inbox.put((t, m)))
        share.declare_publishers(*PUBLISHES, "sim/bodies", on_demand=ON_DEMAND)
        robots[name] = share
    for share in robots.values():
        share.ready()
    node.shares = list(robots.values())   # closed with the session (kept referenced)

    def publish(topic: str, msg) -> None:
        if topic == "sim/people":   # the world's, not a robot's: on the driver's namespace
            node.publish(topic, msg)
            return
        name, _, suffix = topic.partition("/")
        if name in robots and suffix:
            robots[name].publish(suffix, msg)
        else:   # the loop's own (a lockstep fault's event): every robot's
            for share in robots.values():
                share.publish(topic, msg)
    return publish


def build_parser() -> argparse.ArgumentParser:
    parser = ArgumentParser(prog="python -m nodes.world_sim",
                            description=plain(__doc__.split("\n\n")[0]),
                            formatter_class=argparse.RawDescriptionHelpFormatter,
                            epilog=plain(__doc__.split("\n\n", 1)[1]) + "\n"
                            + describe(PORTS, VARIANTS))
    add_driver_args(parser)
    add_zenoh_args(parser)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return run(args)
    except PapfError as exc:
        print(f"world_sim: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    exit_fast(main())   # the session is closed: skip the interpreter's slow teardown
