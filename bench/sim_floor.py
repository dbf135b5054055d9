"""The floor of a lockstep run: the same chain as ``papf run``, in one process, no bus.

World simulator core (physics) -> LiDAR cast -> planner loop -> command, the energy meter on every
odometry/wheels pair, every message encoded once per put and decoded once per subscriber
of the ``sim`` profile (as the processes do) — the same objects the nodes compute, so the
run's sim time of ``reached`` comes out as the stack's. Thread CPU seconds per part, and
the wall time of the chain alone: what ``papf run`` would take with free transport,
start-up and shut-down. A Zenoh hop (put -> other process's callback -> its main thread)
is timed separately (:func:`hop_latency`), as a ping-pong between two processes.

Used by ``papf bench sim --floor``.
"""

from __future__ import annotations

import subprocess
import sys
import time
from collections import Counter

from nodes.energy_meter.core import EnergyMeter
from nodes.lidar_sim.core import LidarParams, LidarSim
from nodes.planner.loop import PlannerLoop
from nodes.planner.registry import make_planner, one_with_role
from nodes.world_sim.core import WorldConfig, WorldCore
from worlds import load_world
from worlds.messages import goal_message

# subscribers per topic in the sim profile (papf run, no recorder): who decodes each put
SUBSCRIBERS = {"sim/pose": 2, "odom": 2, "wheels": 1, "clock": 1, "scan": 1, "cmd_vel": 2,
               "planner/state": 0, "planner/status": 1, "battery": 1, "events": 3}


class _Timer:
    def __init__(self) -> None:
        self.cpu: Counter[str] = Counter()

    def __call__(self, part: str, fn, *args):
        t0 = time.thread_time()
        out = fn(*args)
        self.cpu[part] += time.thread_time() - t0
        return out


def chain(world_name: str = "energy", planner_name: str | None = None, seed: int = 1,
          timeout_s: float = 300.0) -> dict:
    """Run the lockstep chain in-process until the planner's outcome (or the timeout);
    the planner by default the PAPF paper's baseline (APF)."""
    world = load_world(world_name)
    core = WorldCore(world, seed, WorldConfig())
    lidar = LidarSim(world, LidarParams(), seed)
    loop = PlannerLoop(make_planner(planner_name or one_with_role("papf-baseline")))
    meter = EnergyMeter("motor")
    tm, puts, wall0 = _Timer(), Counter(), time.perf_counter()
    loop.on_message("goal", goal_message(world), 0.0)
    outcome, end_ns = "timeout", int(timeout_s * 1e9)
    while core.t_ns <= end_ns and outcome == "timeout":
        out = tm("driver outputs", core.outputs)
        _codec(tm, puts, out)
        by_topic = dict(out)   # a world with people also puts sim/people and sim/bodies
        odom, wheels = by_topic["odom"], by_topic["wheels"]
        for msg in (odom, wheels):
            battery = tm("energy meter", meter.feed, msg)
        _codec(tm, puts, [("battery", battery)])
        if by_topic.get("sim/bodies") is not None:   # the people where the LiDAR sees them
            tm("lidar cast", lidar.place_bodies, by_topic["sim/bodies"])
        if core.is_scan_instant():
            scan = tm("lidar cast", lidar.scan, odom.x, odom.y, odom.yaw, odom.stamp_ns)
            answer = tm("planner", loop.on_message, "odom", odom, 0.0) + \
                tm("planner", loop.on_message, "scan", scan, 0.0)
            _codec(tm, puts, [("scan", scan), *answer])
            for topic, msg in answer:
                if topic == "cmd_vel":
                    core.command(msg)
                elif topic == "planner/status" and msg.state in ("reached", "stagnated", "failed"):
                    outcome = msg.state
        tm("driver physics", core.advance)
    wall = time.perf_counter() - wall0
    sim_s = (core.t_ns - core.config.odom_period_ns) / 1e9
    cycles = max(1, round(sim_s * 1e9 / core.config.scan_period_ns))
    core.close()
    lidar.close()
    chain_cpu = sum(v for k, v in tm.cpu.items() if k in CHAIN)
    return {"outcome": outcome, "sim_s": round(sim_s, 3), "cycles": cycles,
            "wall_s": round(wall, 3), "sim_over_wall": round(sim_s / wall, 1),
            "cpu_s": {k: round(v, 3) for k, v in tm.cpu.most_common()},
            "us_per_cycle": {k: round(v / cycles * 1e6, 1) for k, v in tm.cpu.most_common()},
            "chain_us_per_cycle": round(chain_cpu / cycles * 1e6, 1),
            "chain_sim_over_cpu": round(sim_s / max(chain_cpu, 1e-9), 1),
            "puts_per_cycle": round(sum(puts.values()) / cycles, 1),
            "deliveries_per_cycle": round(sum(n * SUBSCRIBERS.get(t, 0)
                                              for t, n in puts.items()) / cycles, 1)}


# the parts on the lockstep chain (the others run beside it, on the other core)
CHAIN = ("driver outputs", "driver physics", "lidar cast", "planner")


def _codec(tm: _Timer, puts: Counter, out) -> None:
    for topic, msg in out:
        if msg is None:
            continue
        puts[topic] += 1
        data = tm("encode", msg.to_bytes)
        for _ in range(SUBSCRIBERS.get(topic, 0)):
            tm("decode", type(msg).from_bytes, data)


ECHO = """
import sys, time, zenoh
sys.path.insert(0, {root!r})
from common.transport import direct, zenoh_config
with zenoh.open(zenoh_config("peer", [{endpoint!r}])) as s:
    pub = s.declare_publisher("floor/pong")
    sub = s.declare_subscriber("floor/ping", direct(lambda smp: pub.put(smp.payload.to_bytes())))
    s.put("floor/ready", b"")
    time.sleep({life})
"""


def hop_latency(n: int = 300, root: str = ".") -> dict:
    """One Zenoh hop [us]: half a ping-pong with an echo peer in another process (the
    median and the minimum of ``n``; the echo answers from its receiving thread)."""
    import queue

    import zenoh

    from common.transport import direct, zenoh_config
    from papf.launch.supervisor import free_port

    endpoint = f"tcp/127.0.0.1:{free_port()}"
    inbox: queue.SimpleQueue = queue.SimpleQueue()
    with zenoh.open(zenoh_config("router", listen=[endpoint])) as s:
        ready = s.declare_subscriber("floor/ready", direct(lambda smp: inbox.put(None)))
        pong = s.declare_subscriber("floor/pong", direct(lambda smp: inbox.put(time.perf_counter())))
        echo = subprocess.Popen([sys.executable, "-c", ECHO.format(root=root, endpoint=endpoint,
                                                                    life=30 + n * 0.02)])
        try:
            inbox.get(timeout=30)
            time.sleep(0.5)   # peers linked
            pub, rtts = s.declare_publisher("floor/ping"), []
            for _ in range(n):
                t0 = time.perf_counter()
                pub.put(b"x" * 64)
                rtts.append(inbox.get(timeout=5) - t0)
                time.sleep(0.002)
        finally:
            echo.kill()
            echo.wait()
        ready.undeclare()
        pong.undeclare()
    rtts.sort()
    return {"hop_us_p50": round(rtts[len(rtts) // 2] / 2 * 1e6, 1),
            "hop_us_min": round(rtts[0] / 2 * 1e6, 1)}
