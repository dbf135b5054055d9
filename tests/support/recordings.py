"""Test data shared by the tiers: a valid sample of every message type and its key
(recorder tests), a synthetic run's recording (report and energy-experiment tests), and a
stand-in for a run through the stack that writes one (:class:`FakeRuns`)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from common.units import NS_PER_S as NS
from nodes.energy_meter.core import EnergyMeter
from nodes.energy_meter.models import WHEEL_RADIUS_M
from nodes.recorder.writer import RunWriter
from schemas import BatteryState, Clock, Event, Keys, Odometry, PlannerStatus, WheelStates
from schemas.keys import TOPICS
from schemas.messages import DebugValue

VALUES = {"int": 123, "float": 1.5, "bool": True, "floats": (1.0, 2.0),
          "points": ((1.0, 2.0), (3.0, 4.0)), "paths": (((0.0, 1.0), (2.0, 3.0)),),
          "strs": ("a", "b")}


def sample(msg_type, stamp_ns: int = 1_000_000):
    """One valid instance of any message type, built from its field table."""
    kwargs = {}
    for name, kind, md in msg_type._FIELDS:
        if name == "stamp_ns":
            kwargs[name] = stamp_ns
        elif kind == "str":
            kwargs[name] = md["choices"][0] if md.get("choices") else "x"
        elif kind == "f32array":
            kwargs[name] = np.arange(8, dtype=np.float32)
        elif kind == "items":
            kwargs[name] = (sample(md["item"], stamp_ns),)
        elif kind == "floats" and md.get("length"):
            kwargs[name] = tuple(float(i) for i in range(md["length"]))
        else:
            kwargs[name] = VALUES[kind]
    if msg_type is DebugValue:   # one payload, the kind's; colours in 0..1
        kwargs.update(kind="points", paths=(), value=math.nan, colour=(0.0, 0.5, 1.0, 1.0))
    return msg_type(**kwargs)


def key_of(msg_type) -> str:
    return Keys("rosbot").key(next(t for t, m in TOPICS.items() if m is msg_type))


STEP_NS = 20_000_000           # 50 Hz, as the sim driver
SPEED = 0.5                    # [m/s] of the synthetic run


def write_synthetic(path: Path, planner: str = "apf", seed: int = 1, end_k: int = 100,
                    total_k: int = 120, speed: float = SPEED, model: str = "paper",
                    outcome: str | None = "reached", meta: dict | None = None,
                  ground_truth: bool = True) -> EnergyMeter:
    """A straight run along x: standing at k = 0, ``speed`` from k = 1; outcome at ``end_k``.

    Samples continue to ``total_k`` (after the outcome, as a real recording does). The
    live battery is what a ``model`` meter gives for the same odom/wheels. Returns that meter.
    """
    meter = EnergyMeter(model)
    run_meta = {"world": "energy", "planner": planner, "seed": str(seed), "namespace": "rosbot",
                "energy_model": model, **(meta or {})}
    run_meta = {k: v for k, v in run_meta.items() if v is not None}   # None: not recorded
    with RunWriter(path, run_meta) as w:
        w.write_message("rosbot/events", Event(stamp_ns=0, kind="run_started", source="test"))
        for k in range(total_k + 1):
            t = k * STEP_NS
            v = speed if k else 0.0
            odom = Odometry(stamp_ns=t, x=speed * t / NS, y=0.0, yaw=0.0, v=v, w=0.0)
            wheels = WheelStates(stamp_ns=t, speed=(v / WHEEL_RADIUS_M,) * 4, torque=(0.05,) * 4)
            for key, msg in (("sim/pose", odom), ("odom", odom), ("wheels", wheels),
                             ("clock", Clock(stamp_ns=t))):
                if key != "sim/pose" or ground_truth:
                    w.write_message(f"rosbot/{key}", msg)
            meter.feed(odom)
            w.write_message("rosbot/battery", meter.feed(wheels))
            if k % 5 == 0:
                state = outcome if (k == end_k and outcome) else "driving"
                w.write_message("rosbot/planner/status", PlannerStatus(stamp_ns=t, state=state))
    return meter


def write_drive(path: Path, n: int, meta: dict) -> Path:
    """A drive along x at 0.1 m/s: ``n`` odometry and battery samples at 50 Hz (12 W, 1 A)
    on ``rosbot/``, with the recording metadata ``meta`` (pictures' and progress tests);
    ``path``."""
    with RunWriter(path, meta) as w:
        for k in range(n):
            t = k * STEP_NS
            w.write_message("rosbot/odom", Odometry(stamp_ns=t, x=0.1 * t / NS, y=0.0, yaw=0.0,
                                                    v=0.1, w=0.0))
            w.write_message("rosbot/battery", BatteryState(stamp_ns=t, voltage=12.0, current=1.0,
                                                           power=12.0, charge_used_mAh=t / NS,
                                                           energy_J=12 * t / NS))
    return path


ODOM_RUN_N = 600               # samples of :func:`write_odom_recording` (12 s at 50 Hz)


def odom_at(i: int) -> Odometry:
    """The ``i``-th odometry sample of :func:`write_odom_recording`: 50 Hz, 0.01 m apart."""
    return Odometry(stamp_ns=i * STEP_NS, x=i * 0.01, y=0.0, yaw=0.0, v=0.1, w=0.0)


def write_odom_recording(path: Path, n: int = ODOM_RUN_N) -> Path:
    """A recording of ``n`` odometry samples on ``rosbot/odom`` in small (2 KiB) chunks, so
    damage and truncation hit some chunks and spare others; ``path``."""
    with RunWriter(path, {"world": "open"}, chunk_size=2048) as w:
        for i in range(n):
            w.write_message("rosbot/odom", odom_at(i), receive_ns=i)
    return path


def write_ros_topics(path: Path) -> Path:
    """An MCAP of ROS-style topics: ``/some/topic`` (maps to a Zenoh key) and ``/bad//topic``
    (maps to none), three CDR messages each; ``path``."""
    from mcap.writer import Writer

    with open(path, "wb") as f:
        w = Writer(f)
        w.start()
        s = w.register_schema("std_msgs/String", "ros2msg", b"string data")
        for topic in ("/some/topic", "/bad//topic"):
            c = w.register_channel(topic, "cdr", s)
            for i in range(3):
                w.add_message(c, log_time=i, publish_time=i, data=b"\x00\x01\x00\x00abc")
        w.finish()
    return path


class FakeRuns:
    """Stands in for papf.launch.run.run: writes a synthetic recording, returns its summary."""

    def __init__(self, charge_error: float = 0.0, cut_first: int = 0):
        self.configs = []
        self.charge_error = charge_error
        self.cut_first = cut_first   # this many first recordings lose their end

    def __call__(self, cfg):
        from papf.launch.outcome import RunResult
        from papf.report import run_metrics

        self.configs.append(cfg)
        speed = (0.4 if cfg.planner == "apf" else 0.5) + 0.01 * cfg.seed
        write_synthetic(Path(cfg.record), cfg.planner, cfg.seed, speed=speed)
        m = run_metrics(cfg.record)
        if len(self.configs) <= self.cut_first:  # the live run was whole; the file is not
            Path(cfg.record).unlink()            # (recordings are never overwritten)
            write_synthetic(Path(cfg.record), cfg.planner, cfg.seed, speed=speed, total_k=80,
                            outcome=None, meta={"timeout_s": "300"})
        return RunResult(m.outcome, cfg.planner, "energy", cfg.seed, m.duration_s,
                         m.path_length_m, m.charge_mAh + self.charge_error, m.energy_J, 0,
                         m.t_end_s, 0.1)
