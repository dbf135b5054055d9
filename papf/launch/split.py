"""``papf run --link PROFILE|SPEC``: the stack split as it is deployed, over an emulated link.

Robot side: its own router and the ``robot`` launch profile's nodes (the rosbot driver, the
LiDAR from ROS 2), plus ``papf rosbot-emulator --world W`` as the robot's body and scan.
Between them and the laptop: ``papf link`` (:mod:`papf.link`). Laptop side: its own router,
joined to the link, and the ``laptop`` profile (planner, energy meter, recorder) driving the
run — :func:`papf.launch.host.launch`, the very code of ``papf launch laptop``. Every process
is on this machine; only the link between the two routers is emulated, as one TCP
connection between two Zenoh routers is what a real Wi-Fi carries.

The link's outage schedule counts from the run's start (``run_started``: the launcher
sends the link SIGUSR1 then), so ``outage=10@20`` is 20 s into the drive, whatever the
start-up took. The result is ``papf run``'s, plus ``link_emulator``: the link's stats.
"""

from __future__ import annotations

import json
import os
import re
import signal
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from common import runauth
from common.errors import ConfigError
from common.units import LOCKSTEP_TIMEOUT_S
from papf.launch.claim import Claim
from papf.launch.host import launch, launch_key
from papf.launch.outcome import RunMonitor, RunResult
from papf.launch.preflight import check_launch
from papf.launch.profile import LaunchOptions, Process, load_profile, resolve
from papf.launch.run import RunConfig
from papf.launch.supervisor import Supervisor, free_port, wait_port
from papf.link.spec import LinkSpec, parse_spec
from worlds import load_world

LOOPBACK = "127.0.0.1"
STALL_S = 20.0          # [s wall] the laptop's default: no robot clock this long = stuck
PORT_WAIT_S = 30.0      # [s wall] for a router or the link to listen


class RobotSideLog:
    """Which robot-side log lines reach stderr, and what the rosbot driver said about the
    commands the link brought it (its watchdog stops as they happen, its late-command count
    when it stops) — ``link_emulator.robot_side`` in the run's JSON. The driver's own link
    figures (link-drive's ``link`` in the JSON) supersede these once it reports them."""

    STOPPED = re.compile(r"stopped: (\d+) commands sent to the robot, (\d+) late ones dropped")

    def __init__(self, verbose: bool):
        self.verbose = verbose
        self.watchdog_stops = 0
        self.sent: int | None = None
        self.late: int | None = None

    def __call__(self, name: str, line: str) -> bool:
        if name == "robot/base_driver":
            if "watchdog: no command" in line:
                self.watchdog_stops += 1
            elif (m := self.STOPPED.search(line)) is not None:
                self.sent, self.late = int(m.group(1)), int(m.group(2))
        return self.verbose or any(k in line for k in ("WARNING", "ERROR", "Traceback", "rror:",
                                                       "papf link:"))

    def to_json(self) -> dict:
        return {"watchdog_stops": self.watchdog_stops, "commands_sent": self.sent,
                "late_commands": self.late}


@dataclass(frozen=True)
class SplitPorts:
    robot: int      # the robot's router
    link: int       # the emulator's listening side
    laptop: int     # the laptop's router


def _ep(port: int) -> str:
    return f"tcp/{LOOPBACK}:{port}"


def laptop_stall_s(spec: LinkSpec) -> float:
    """How long the laptop waits without the robot's clock before it calls the run stuck:
    its default, or longer than the link's longest outage (and TCP's retry after it)."""
    longest = max([length for length, _ in spec.outages]
                  + [5.0 * spec.outage_mean_s if spec.outage_rate_per_min else 0.0])
    return max(STALL_S, 2.0 * longest + 10.0)


def robot_options(cfg: RunConfig, ports: SplitPorts) -> LaunchOptions:
    """The ``robot`` profile on its own router (as ``papf launch robot --listen``)."""
    values = {"world": cfg.world}
    if cfg.robot_record:   # the robot side's own recording: its black box
        values["record"] = cfg.robot_record
        if cfg.force:
            values["record_force"] = "1"
    return LaunchOptions("robot", listen=[_ep(ports.robot)], namespace=cfg.namespace,
                         values=values, startup_timeout_s=cfg.startup_timeout_s,
                         verbose=cfg.verbose)


def laptop_options(cfg: RunConfig, ports: SplitPorts, spec: LinkSpec) -> LaunchOptions:
    """The ``laptop`` profile on the laptop's router (as ``papf launch laptop --connect``)."""
    values = {"world": cfg.world, "planner": cfg.planner, "seed": cfg.seed,
              "energy_model": cfg.energy_model, "record": cfg.record,
              "record_force": "1" if cfg.force and cfg.record else None,
              "objects": cfg.objects, "view": cfg.view,
              "ros_face": None if cfg.ros_face is None else "1", "ros_face_domain": cfg.ros_face}
    extra = dict(cfg.extra_node_args)   # the recording says which link it was made over
    extra["recorder"] = [*extra.get("recorder", ()), "--meta", f"link={spec.to_text()}"]
    return LaunchOptions("laptop", connect=[_ep(ports.laptop)], namespace=cfg.namespace,
                         values={k: v for k, v in values.items() if v is not None},
                         planner_args=list(cfg.planner_args), timeout_s=cfg.timeout_s,
                         startup_timeout_s=cfg.startup_timeout_s, stall_s=laptop_stall_s(spec),
                         verbose=cfg.verbose, extra_node_args=extra)


def side_processes(cfg: RunConfig, ports: SplitPorts, spec: LinkSpec, stats: str,
                   robot_trace: str | None) -> list[Process]:
    """The processes besides the two profiles': the robot's body, the link, the laptop's
    router (``papf run --link --dry-run`` prints them with the profiles')."""
    py = sys.executable
    emulator = [py, "-m", "papf", "rosbot-emulator", "--connect", _ep(ports.robot),
                "--namespace", cfg.namespace, "--world", str(cfg.world), "--seed", str(cfg.seed)]
    if robot_trace:
        emulator += ["--trace", robot_trace]
    link = [py, "-m", "papf", "link", "--listen", _ep(ports.link), "--to", _ep(ports.robot),
            "--spec", spec.to_text(), "--t0", "signal", "--stats", stats]
    router = [py, "-m", "papf.launch.router", "--listen", _ep(ports.laptop), "--join",
              _ep(ports.link)]
    return [Process("rosbot_emulator", "robot", tuple(emulator)),
            Process("link", "link", tuple(link)), Process("router", "laptop", tuple(router))]


def _ports(cfg: RunConfig) -> SplitPorts:
    ports = {cfg.port} if cfg.port else set()
    while len(ports) < 3:
        ports.add(free_port())
    robot = cfg.port or ports.pop()
    ports.discard(robot)
    return SplitPorts(robot, ports.pop(), ports.pop())


def link_spec_of(cfg: RunConfig) -> LinkSpec:
    if not cfg.link:
        raise ConfigError("papf run --link: give a link profile or SPEC")
    return parse_spec(cfg.link)


def resolve_split(cfg: RunConfig) -> str:
    """``papf run --link … --dry-run``: every process of both sides and the link, as JSON."""
    spec = link_spec_of(cfg)
    ports = SplitPorts(cfg.port or 7447, 7448, 7449)
    robot = resolve(load_profile("robot"), robot_options(cfg, ports))
    laptop = resolve(load_profile("laptop"), laptop_options(cfg, ports, spec))
    procs = ([dict(p.to_json(), host="robot") for p in robot.processes]
             + [p.to_json() for p in side_processes(cfg, ports, spec, "STATS.json",
                                                    cfg.robot_trace)]
             + [p.to_json() for p in laptop.processes])
    return json.dumps({"profile": "split", "link": spec.describe(), "processes": procs}, indent=1)


def _check(cfg: RunConfig, spec: LinkSpec, ports: SplitPorts) -> None:
    """Both profiles' preflight, before anything starts (ConfigError: exit 2, one line)."""
    load_world(cfg.world)
    if cfg.odom_hz is not None:   # the robot side is the ROSbot's (its emulator): its own rate
        raise ConfigError("--odom-hz: the simulator's odometry rate; with --link the "
                          "robot side is the ROSbot's emulator at its own 50 Hz: drop --odom-hz")
    if cfg.lockstep_timeout_s != LOCKSTEP_TIMEOUT_S:   # a split run is real time: nothing waits
        raise ConfigError("--lockstep-timeout: a lockstep run's; a run with --link goes at the "
                          "wall clock's pace and never waits for a command: drop --lockstep-timeout")
    check_launch(robot_options(cfg, ports), load_profile("robot"))
    laptop = laptop_options(cfg, ports, spec)
    check_launch(laptop, load_profile("laptop"))
    resolve(load_profile("laptop"), laptop)    # --objects truth: not on a real robot
    if cfg.robot_trace:
        from common.outfiles import check_output

        check_output(cfg.robot_trace, force=True)   # appended to, as the emulator does


def run_split(cfg: RunConfig) -> RunResult:
    """Run the split stack once over the emulated link; every process stopped at the end."""
    spec = link_spec_of(cfg)
    ports = _ports(cfg)
    _check(cfg, spec, ports)
    wall0 = time.monotonic()
    robot = resolve(load_profile("robot"), robot_options(cfg, ports))
    with tempfile.TemporaryDirectory(prefix="papf-link-") as tmp:
        stats_file = Path(tmp) / "link-stats.json"
        extra = {p.name: p for p in side_processes(cfg, ports, spec, str(stats_file),
                                                   cfg.robot_trace)}
        robot_log = RobotSideLog(cfg.verbose)
        # both sides seal with this host's pairing key, as two launches on one host would
        key = launch_key(load_profile("robot"), robot_options(cfg, ports))
        with Claim(cfg.namespace, "robot", robot.nodes), \
                Supervisor(show=robot_log, env={runauth.ENV: key}) as sup:
            result = _start_and_drive(cfg, ports, spec, robot, extra, sup)
        result.link_emulator = _read_stats(stats_file)
        if result.link_emulator is not None:
            result.link_emulator["robot_side"] = robot_log.to_json()
    result.wall_time_s = time.monotonic() - wall0
    return result


def _failed(cfg: RunConfig, reason: str) -> RunResult:
    monitor = RunMonitor(cfg.timeout_s)
    monitor.fail(reason)
    return monitor.result(cfg.planner, load_world(cfg.world).name, cfg.seed, 0.0)


def _start_and_drive(cfg: RunConfig, ports: SplitPorts, spec: LinkSpec, robot, extra: dict,
                     sup: Supervisor) -> RunResult:
    """Robot side, link, laptop router (each listening before the next), then the laptop's
    launch drives the run; a robot-side death names that side in the reason."""
    sup.start("robot/router", list(robot.processes[0].argv))
    if not wait_port(ports.robot, PORT_WAIT_S, abort=lambda: bool(sup.dead())):
        return _failed(cfg, "the robot's router did not come up: " + sup.death_reason())
    for name, argv in robot.nodes.items():
        sup.start(f"robot/{name}", argv)
    sup.start("robot/rosbot_emulator", list(extra["rosbot_emulator"].argv))
    link = sup.start("link", list(extra["link"].argv))
    if not wait_port(ports.link, PORT_WAIT_S, abort=lambda: bool(sup.dead())):
        return _failed(cfg, "the link emulator did not come up: " + sup.death_reason())
    sup.start("laptop/router", list(extra["router"].argv))
    if not wait_port(ports.laptop, PORT_WAIT_S, abort=lambda: bool(sup.dead())):
        return _failed(cfg, "the laptop's router did not come up: " + sup.death_reason())

    def start_outages() -> None:   # the link's t0: the run's start
        if link.proc.poll() is None:
            os.kill(link.proc.pid, signal.SIGUSR1)
    result = launch(laptop_options(cfg, ports, spec), on_run_start=start_outages)
    if result.outcome == "failed" and sup.dead():
        result.reason = f"robot side: {sup.death_reason()} ({result.reason})"
    return result


def _read_stats(path: Path) -> dict | None:
    """The link's stats file (written when it stopped), or None if it wrote none."""
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
