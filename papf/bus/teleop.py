"""``papf teleop``: drive the robot from the keyboard, like ``teleop_twist_keyboard``.

The commands go where the planner's go (``<ns>/cmd_vel``), so the base driver's
:class:`common.drive.CommandGate` clamps, rate-limits and watchdogs them alike.
:class:`TeleopState` is pure (keys -> speeds; tests drive it); :func:`run` owns the
terminal. Used by ``papf teleop``.
"""

from __future__ import annotations

import contextlib
import math
import os
import select
import sys
import termios
import time
import tty
from collections.abc import Callable
from dataclasses import dataclass

import zenoh

from common import robot, runauth
from common.errors import ConfigError, PapfError
from common.seal import Sealer
from schemas import Clock, Event, Keys, Odometry, Twist

ARROWS = {"\x1b[A": "up", "\x1b[B": "down", "\x1b[C": "right", "\x1b[D": "left"}
ACTIONS = {"w": "faster", "up": "faster", "s": "slower", "down": "slower",
           "a": "left", "left": "left", "d": "right", "right": "right",
           " ": "stop", "x": "stop", "q": "quit", "\x03": "quit", "\x04": "quit"}
HELP = "w/s or up/down: speed, a/d or left/right: turn, space: stop, q: quit"
EXIT_ZEROS = 3   # zero commands sent on quit


def parse_keys(text: str) -> list[str]:
    """Key names in typed order: arrow escape sequences become up/down/left/right."""
    keys, i = [], 0
    while i < len(text):
        seq = text[i:i + 3]
        if seq in ARROWS:
            keys.append(ARROWS[seq])
            i += 3
        else:
            keys.append(text[i].lower())
            i += 1
    return keys


@dataclass
class TeleopState:
    """The command the keys have set: steps up/down within the teleop's own limits."""

    max_v: float = 0.3       # [m/s] teleop limit (a first drive; the driver's is 0.9)
    max_w: float = 1.0       # [rad/s]
    step_v: float = 0.05     # [m/s] per key press
    step_w: float = 0.2      # [rad/s] per key press
    v: float = 0.0
    w: float = 0.0
    quit: bool = False

    def __post_init__(self) -> None:
        for name, value, limit in (("max_v", self.max_v, robot.V_MAX_M_S),
                                   ("max_w", self.max_w, robot.W_MAX_RAD_S)):
            if not (math.isfinite(value) and 0 < value <= limit):
                raise ConfigError(f"teleop {name} {value!r} must be > 0 and <= the ROSbot's "
                                  f"{limit} (the driver clamps there anyway)")
        for name in ("step_v", "step_w"):
            if not (getattr(self, name) > 0):
                raise ConfigError(f"teleop {name} must be > 0")

    def press(self, key: str) -> bool:
        """Apply one key; False if it means nothing. Sets :attr:`quit` on q."""
        action = ACTIONS.get(key)
        if action == "faster":
            self.v = _clamp(self.v + self.step_v, self.max_v)
        elif action == "slower":
            self.v = _clamp(self.v - self.step_v, self.max_v)
        elif action == "left":
            self.w = _clamp(self.w + self.step_w, self.max_w)
        elif action == "right":
            self.w = _clamp(self.w - self.step_w, self.max_w)
        elif action == "stop":
            self.v = self.w = 0.0
        elif action == "quit":
            self.v = self.w = 0.0
            self.quit = True
        return action is not None

    def status(self) -> str:
        """The command on screen: ``v +0.10 m/s  w -0.50 rad/s``."""
        return f"v {self.v:+.2f} m/s  w {self.w:+.2f} rad/s"


def _clamp(x: float, limit: float) -> float:
    return round(max(-limit, min(limit, x)), 6)   # no 0.15000000000000002 on screen


class _Bus:
    """Publisher of cmd_vel plus the latest clock stamp and odometry the driver publishes."""

    def __init__(self, session: zenoh.Session, keys: Keys, key: bytes | None = None):
        self.session, self.keys = session, keys
        # sealed outside any run with this host's key (common.seal): a keyed driver between
        # runs obeys it, and no run's planner is overruled (a driver in a run refuses it)
        self.sealer = Sealer(key) if key is not None else None
        self.stamp_ns = 0
        self.odom: Odometry | None = None
        self.pub = session.declare_publisher(keys.cmd_vel,
                                             congestion_control=zenoh.CongestionControl.BLOCK)
        self.subs = [session.declare_subscriber(keys.clock, self._on_clock),
                     session.declare_subscriber(keys.odom, self._on_odom)]

    def _on_clock(self, sample: zenoh.Sample) -> None:
        with contextlib.suppress(Exception):
            self.stamp_ns = max(self.stamp_ns, Clock.from_bytes(sample.payload.to_bytes()).stamp_ns)

    def _on_odom(self, sample: zenoh.Sample) -> None:
        with contextlib.suppress(Exception):
            self.odom = Odometry.from_bytes(sample.payload.to_bytes())

    def send(self, v: float, w: float) -> None:
        payload = Twist(stamp_ns=self.stamp_ns, v=v, w=w).to_bytes()
        if self.sealer is None:
            self.pub.put(payload)
        else:
            self.pub.put(payload, attachment=self.sealer.seal(self.keys.cmd_vel, payload))

    def close(self) -> None:
        for s in self.subs:
            s.undeclare()
        self.pub.undeclare()


def teleop_key(namespace: str, key_file: str | None = None) -> bytes | None:
    """The key a teleop seals with: ``key_file`` (``--key``), else this host's pairing key
    (``papf launch robot`` on this host), else none (a driver started alone takes anything)."""
    if key_file is not None:
        return runauth.load_pair_key(key_file)[0]
    path = runauth.pair_file(namespace)
    try:
        return runauth.load_pair_key(path)[0] if path.exists() else None
    except PapfError:
        return None


@contextlib.contextmanager
def cbreak(fd: int):
    """Keys arrive one by one, unechoed; Ctrl-C still raises KeyboardInterrupt."""
    old = termios.tcgetattr(fd)
    try:
        tty.setcbreak(fd)
        yield
    finally:
        termios.tcsetattr(fd, termios.TCSADRAIN, old)


def run(session: zenoh.Session, keys: Keys, state: TeleopState, *, period_s: float = 0.1,
        start_run: bool = False, fd: int | None = None, out=None,
        stop: Callable[[], bool] = lambda: False) -> int:
    """Read keys from the terminal ``fd`` and publish commands until q; returns the exit code.

    Each command carries the latest ``<ns>/clock`` stamp (the driver's time; 0 before a run),
    as a planner's carries its scan's; the gate's 0.5 s watchdog stops the robot when commands
    cease (a killed teleop, a cut link).

    Keys (:func:`parse_keys`): ``w``/up faster forward, ``s``/down slower or backwards,
    ``a``/left turn left (counter-clockwise), ``d``/right turn right, space or ``x`` stop,
    ``q`` (or Ctrl-C) quit — zero velocity is sent on the way out. The speed set is kept and
    re-sent every ``period_s`` (default 0.1 s) until changed.
    """
    fd = sys.stdin.fileno() if fd is None else fd
    out = out or sys.stdout
    if not os.isatty(fd):
        raise ConfigError("papf teleop reads the keyboard: run it in a terminal (stdin is not one)")
    key = teleop_key(keys.ns)
    bus = _Bus(session, keys, key)
    try:
        if start_run:
            runauth.sealed_put(session, keys.events, Event(
                stamp_ns=0, kind="run_started", source="papf-teleop", detail="teleop").to_bytes(),
                key)
        with cbreak(fd):   # discards keys typed before it: the banner says it is listening
            out.write(f"papf teleop on {keys.cmd_vel}: {HELP}\r\n")
            out.flush()
            _loop(bus, state, fd, period_s, out, stop)
    except KeyboardInterrupt:
        state.press("q")
    finally:
        for _ in range(EXIT_ZEROS):
            bus.send(0.0, 0.0)
        bus.close()
        out.write("\r\nstopped: zero velocity sent\r\n")
        out.flush()
    return 0


def _loop(bus: _Bus, state: TeleopState, fd: int, period_s: float, out, stop) -> None:
    next_send = time.monotonic()
    while not state.quit and not stop():
        now = time.monotonic()
        if now >= next_send:
            bus.send(state.v, state.w)
            next_send = now + period_s
            out.write("\r" + state.status() + _pose(bus.odom) + "   ")
            out.flush()
        ready, _, _ = select.select([fd], [], [], max(next_send - time.monotonic(), 0.0))
        if ready:
            data = os.read(fd, 64).decode("utf-8", "replace")
            if not data:    # the terminal closed: stop
                state.press("q")
            for key in parse_keys(data):
                if state.press(key):
                    next_send = 0.0   # a change goes out at once


def _pose(odom: Odometry | None) -> str:
    if odom is None:
        return "   (no odometry yet)"
    return f"   odom x {odom.x:+.2f} y {odom.y:+.2f} m  yaw {math.degrees(odom.yaw):+.0f}°"
