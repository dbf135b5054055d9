"""Where the world simulator's share of a fleet cycle goes, in-process (no bus): ``papf bench
fleet --driver-split 8,16``.

The simulator's core (:class:`nodes.world_sim.core.WorldCore`) of the bench's lanes world with
R robots is stepped through ``--long-s`` of sim time as the lockstep would (every robot's
command answers every scan), each message encoded as the node would put it. The CPU time
(``time.process_time``; the machine's other work does not count, though it cools the caches)
is split by what the driver does, per robot per 100 ms cycle:

- ``tyres_ms``: the Coulomb tyre forces (three pybullet reads, four forces per robot per 4 ms);
- ``contacts_ms``: each robot's chassis contacts after each step;
- ``gate_ms``: the command gates (limits, watchdog) per robot per step;
- ``physics_ms``: the rest of the steps: Bullet's ``stepSimulation`` and the motors' targets;
- ``messages_ms``: every instant's messages built and encoded (poses, odometry, wheels,
  clock, ``sim/bodies``).
"""

from __future__ import annotations

import time
from pathlib import Path

from common import drive as drive_mod
from nodes.world_sim import core as core_mod
from nodes.world_sim import physics as sim_mod
from schemas.messages import Twist
from worlds import load_world

SPLIT_FIELDS = ("label", "robots", "sim_s", "cpu_ms_per_robot_cycle", "physics_ms", "tyres_ms",
                "contacts_ms", "gate_ms", "messages_ms", "load_avg_1min")
_PARTS = ("tyres", "contacts", "gate", "messages")


def _timed(totals: dict, part: str, fn):
    def wrapper(*a, **k):
        t0 = time.process_time()
        try:
            return fn(*a, **k)
        finally:
            totals[part] += time.process_time() - t0
    return wrapper


def split(world_file: Path, sim_s: float, warm_s: float = 1.0) -> dict:
    """The driver's CPU split for the world (module doc), per robot per 100 ms cycle [ms]."""
    totals = dict.fromkeys(_PARTS, 0.0)
    patches = [(sim_mod.SimBase, "_apply_tyre_forces", "tyres"), (sim_mod.SimBase, "contacts", "contacts"),
               (drive_mod.CommandGate, "output", "gate"), (core_mod.WorldCore, "outputs", "messages")]
    saved = [(cls, name, getattr(cls, name)) for cls, name, _ in patches]
    for cls, name, part in patches:
        setattr(cls, name, _timed(totals, part, getattr(cls, name)))
    try:
        with core_mod.WorldCore(load_world(str(world_file)), 0) as drv:
            n = len(drv.names)

            def run(seconds: float) -> None:
                for _ in range(round(seconds / 0.02)):
                    for _, msg in drv.outputs():
                        msg.to_bytes()
                    if drv.is_scan_instant():
                        for name in drv.names:
                            drv.command(Twist(stamp_ns=drv.t_ns, v=0.3, w=0.0), name)
                    drv.advance()
            run(warm_s)
            for k in totals:
                totals[k] = 0.0
            t0 = time.process_time()
            run(sim_s)
            total = time.process_time() - t0
    finally:
        for cls, name, fn in saved:
            setattr(cls, name, fn)
    cycles = n * sim_s / 0.1
    row = {"robots": n, "sim_s": sim_s, "cpu_ms_per_robot_cycle": round(total / cycles * 1e3, 3),
           "physics_ms": round((total - sum(totals.values())) / cycles * 1e3, 3)}
    row.update({f"{k}_ms": round(v / cycles * 1e3, 3) for k, v in totals.items()})
    return row
