"""The robot side of driving over a slow link: follow the freshest plan (pure; docs/link-driving.md).

A realtime command carries the planner's short plan (``Twist.plan``: poses at
``stamp + k dt``, pose 0 = the one it was computed for; ``nodes/planner/rollout.py``). It
reaches the robot a round trip after its stamp; the follower uses it at the time it is
used, with the robot's own odometry: at run time ``t`` it tracks the plan's reference pose
of ``t`` with Kanayama et al.'s law (1990, "A stable tracking control method for an
autonomous mobile robot", eq. 3; the heading term in 1/s, ours):

    v = v_r cos e_th + k_x e_x
    w = w_r + v_r k_y e_y + k_th sin e_th

(e = the reference pose in the robot's frame), limited to the plan's own top speed and
scaled down as the plan ages (:func:`age_scale`).

When a command may be obeyed (exactly; run time ``t``, arrival ``r``, stamp ``s``, the
driver's watchdog ``W``, ``max_plan_age`` ``A``):

- it arrived no more than ``W`` ago: ``t - r <= W`` (the watchdog: a silent link stops the
  base), and it is not older than the plan already followed (``s`` greater);
- a plan: ``t <= min(plan end, s + A')``, ``A' = A`` while the robot's collision monitor has
  a fresh scan of its own, else ``A' = W`` — the robot drives on an old plan only when it
  can see for itself;
- a plain command (no plan: teleop): ``r <= s + W`` when it arrives (as before);
- a stop (v = w = 0, no plan) is obeyed whenever it is not older than the newest command
  obeyed that was not a stop: stopping is never too late, and a later plan resumes;
- a command stamped more than ``W`` ahead of the robot's clock is refused (a stamp a little
  ahead comes from a tool whose clock started before the robot's: taken as fresh);
- a plan whose reference lies more than ``MAX_TRACKING_ERROR_M`` from the robot is not
  chased: the base stops.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

from common.params import check_value, num
from schemas import Twist

SPECS = {
    # safety: the plan's age the robot still drives on; 2 s is the watchdog's own ceiling
    "max_plan_age": num(0.1, 2.0, "s", safety=True),
}
FULL_SPEED_AGE_S = 0.25      # [s] a plan this fresh is driven at full speed (ours)
MIN_SPEED_SCALE = 0.25       # [-] the scale at max_plan_age (ours)
MAX_TRACKING_ERROR_M = 0.5   # [m] farther from the reference than this: stop, don't chase (ours)
K_X, K_Y, K_TH = 1.0, 4.0, 2.0   # [1/s], [1/m^2], [1/s] tracking gains (ours)
HEADING_M_PER_RAD = 0.1      # [m/rad] heading's weight when joining a plan (ours)
W_CORRECTION = 0.5           # [rad/s] turn rate the tracking may add to the plan's own (ours)
PLAN_DT_NS = (10_000_000, 1_000_000_000)   # a plan's step must lie in [10 ms, 1 s]
MAX_POSES = 201


@dataclass(frozen=True)
class FollowSettings:
    max_plan_age: float = 1.5     # [s] (docs/link-driving.md "The choice")

    def __post_init__(self) -> None:
        for name, spec in SPECS.items():
            check_value(name, getattr(self, name), spec)


class Target(NamedTuple):
    v: float
    w: float
    why: str          # "" while following; else why the target is a stop
    scale: float      # the age scale applied


def age_scale(age_s: float, max_age_s: float) -> float:
    """1 up to FULL_SPEED_AGE_S, falling linearly to MIN_SPEED_SCALE at ``max_age_s``."""
    if age_s <= FULL_SPEED_AGE_S or max_age_s <= FULL_SPEED_AGE_S:
        return 1.0
    frac = min(1.0, (age_s - FULL_SPEED_AGE_S) / (max_age_s - FULL_SPEED_AGE_S))
    return 1.0 - (1.0 - MIN_SPEED_SCALE) * frac


def plan_error(cmd: Twist) -> str:
    """Why ``cmd``'s plan cannot be followed ('' = it can, or it has none)."""
    if not cmd.plan and not cmd.plan_dt_ns:
        return ""
    n = len(cmd.plan)
    if n % 3 or not 2 <= n // 3 <= MAX_POSES:
        return f"a plan of {n} numbers is not 2..{MAX_POSES} (x, y, yaw) poses"
    if not PLAN_DT_NS[0] <= cmd.plan_dt_ns <= PLAN_DT_NS[1]:
        return f"plan step {cmd.plan_dt_ns} ns is not in [{PLAN_DT_NS[0]}, {PLAN_DT_NS[1]}] ns"
    return ""


class PlanFollower:
    """The command the base follows now (see module doc); time is the robot's run time [ns]."""

    def __init__(self, watchdog_ns: int, settings: FollowSettings | None = None):
        self.s = settings or FollowSettings()
        self.watchdog_ns = watchdog_ns
        self.cmd: Twist | None = None
        self.arrived_ns = 0
        self.newest_ns: int | None = None   # stamp of the newest command that was not a stop
        self.shift_ns = 0                   # the plan is followed at t + shift (join)

    def take(self, cmd: Twist, now_ns: int, monitor_fresh: bool,
             pose: tuple[float, float, float] | None = None) -> tuple[str, str]:
        """A command arriving at ``now_ns``: ("obeyed" | "late" | "stale", why). ``pose``: the
        robot's now, where the plan is joined (:func:`join`)."""
        stop = cmd.v == 0.0 and cmd.w == 0.0 and not cmd.plan
        floor = self.newest_ns
        if floor is not None and (cmd.stamp_ns < floor or (cmd.stamp_ns == floor and not stop)):
            return "stale", (f"answers the scan of {cmd.stamp_ns * 1e-9:.3f} s, not newer than "
                             f"the command followed ({floor * 1e-9:.3f} s)")
        why = plan_error(cmd)
        if why:
            return "late", why
        if cmd.stamp_ns > now_ns + self.watchdog_ns:   # a clock not the robot's (a tool's)
            return "late", f"stamped {(cmd.stamp_ns - now_ns) * 1e-9:.3f} s in the future"
        end = self.valid_until(cmd, now_ns, monitor_fresh)
        if now_ns > end and not stop:   # a stop is never too late to obey
            return "late", (f"{(now_ns - cmd.stamp_ns) * 1e-9:.3f} s old on arrival, valid "
                            f"{(end - cmd.stamp_ns) * 1e-9:.3f} s")
        self.cmd, self.arrived_ns = cmd, now_ns
        self.shift_ns = join(cmd, now_ns, pose) if cmd.plan and pose is not None else 0
        if not stop:   # a stop halts the plan; the next plan newer than the last one resumes
            self.newest_ns = cmd.stamp_ns
        return "obeyed", ""

    def valid_until(self, cmd: Twist, arrived_ns: int, monitor_fresh: bool) -> int:
        """Run time [ns] up to which ``cmd`` may be obeyed (the module doc's rules)."""
        if not cmd.plan:   # late when it comes after stamp + W; else held for W after arrival
            late = arrived_ns > cmd.stamp_ns + self.watchdog_ns and (cmd.v, cmd.w) != (0.0, 0.0)
            return cmd.stamp_ns + self.watchdog_ns if late else arrived_ns + self.watchdog_ns
        end = cmd.stamp_ns + (len(cmd.plan) // 3 - 1) * cmd.plan_dt_ns
        age_ns = int(self.s.max_plan_age * 1e9) if monitor_fresh else self.watchdog_ns
        return min(end, cmd.stamp_ns + age_ns, arrived_ns + self.watchdog_ns)

    def target(self, now_ns: int, pose: tuple[float, float, float] | None,
               monitor_fresh: bool) -> Target:
        """The (v, w) to follow at ``now_ns`` from robot ``pose`` (world frame; None: unknown)."""
        cmd = self.cmd
        if cmd is None:
            return Target(0.0, 0.0, "no command yet", 1.0)
        if now_ns - self.arrived_ns > self.watchdog_ns:
            return Target(0.0, 0.0, f"no command for {(now_ns - self.arrived_ns) * 1e-9:.3f} s "
                          f"(watchdog {self.watchdog_ns * 1e-9:g} s)", 1.0)
        if now_ns > self.valid_until(cmd, self.arrived_ns, monitor_fresh):
            return Target(0.0, 0.0, f"the plan of {cmd.stamp_ns * 1e-9:.3f} s ran out "
                          f"({(now_ns - cmd.stamp_ns) * 1e-9:.3f} s old)", 1.0)
        if not cmd.plan:
            return Target(cmd.v, cmd.w, "", 1.0)
        if pose is None:
            return Target(0.0, 0.0, "no odometry to follow the plan with", 1.0)
        scale = age_scale((now_ns - cmd.stamp_ns) * 1e-9, self.s.max_plan_age)
        v, w, err = track(cmd, now_ns + self.shift_ns, pose)
        if err > MAX_TRACKING_ERROR_M:
            return Target(0.0, 0.0, f"the plan's reference is {err:.2f} m away: not chased", scale)
        return Target(v * scale, w * scale, "", scale)


def join(cmd: Twist, now_ns: int, pose: tuple[float, float, float]) -> int:
    """Where along the plan the robot is when the plan arrives: the shift [ns, <= 0] from
    the plan's time of ``now_ns`` to that of its pose nearest the robot (position, plus
    HEADING_M_PER_RAD per radian of heading, so a turn in place is joined by its heading).

    A robot that kept up with the plans before is where the plan says (shift 0); one that
    stood still (the first plan, after a stop) starts the plan from its beginning instead
    of chasing the point the plan reached meanwhile. Validity is still counted from the
    stamp: joining never makes a plan live longer.
    """
    p, dt = cmd.plan, cmd.plan_dt_ns
    x, y, yaw = pose
    age_k = min(len(p) // 3 - 1, max(0, (now_ns - cmd.stamp_ns) // dt))
    best, best_k = math.inf, age_k
    for k in range(age_k + 1):
        d = (math.hypot(p[3 * k] - x, p[3 * k + 1] - y)
             + HEADING_M_PER_RAD * abs(math.atan2(math.sin(p[3 * k + 2] - yaw),
                                                  math.cos(p[3 * k + 2] - yaw))))
        if d < best - 1e-9:
            best, best_k = d, k
    return min(0, best_k * dt - (now_ns - cmd.stamp_ns))


def reference(cmd: Twist, t_ns: int) -> tuple[float, ...]:
    """The plan's pose (x, y, yaw) at ``t_ns``, its speed v_r [m/s], turn rate w_r [rad/s],
    and its top speed [m/s] and turn rate [rad/s] over the whole plan; linear between poses."""
    p, dt = cmd.plan, cmd.plan_dt_ns
    n = len(p) // 3
    k = min(max(0, (t_ns - cmd.stamp_ns) // dt), n - 2)
    f = min(1.0, max(0.0, (t_ns - cmd.stamp_ns - k * dt) / dt))
    x0, y0, a0, x1, y1, a1 = p[3 * k:3 * k + 6]
    dts = dt * 1e-9
    heading = math.cos(a0) * (x1 - x0) + math.sin(a0) * (y1 - y0)   # forward (+) or back (-)
    v_r = math.copysign(math.hypot(x1 - x0, y1 - y0), heading) / dts
    top = max(math.hypot(p[3 * i + 3] - p[3 * i], p[3 * i + 4] - p[3 * i + 1])
              for i in range(n - 1)) / dts
    turn = max(abs(p[3 * i + 5] - p[3 * i + 2]) for i in range(n - 1)) / dts
    return (x0 + f * (x1 - x0), y0 + f * (y1 - y0), a0 + f * (a1 - a0), v_r, (a1 - a0) / dts,
            top, turn)


def track(cmd: Twist, t_ns: int, pose: tuple[float, float, float]) -> tuple[float, float, float]:
    """Kanayama's tracking law towards the plan's reference at ``t_ns`` (module doc);
    (v, w, distance to the reference)."""
    xr, yr, ar, v_r, w_r, top, turn = reference(cmd, t_ns)
    x, y, yaw = pose
    c, s = math.cos(yaw), math.sin(yaw)
    ex, ey = c * (xr - x) + s * (yr - y), -s * (xr - x) + c * (yr - y)
    eth = math.atan2(math.sin(ar - yaw), math.cos(ar - yaw))
    v = v_r * math.cos(eth) + K_X * ex
    w = w_r + v_r * K_Y * ey + K_TH * math.sin(eth)
    v = max(-top, min(top, v))   # never faster than the planner itself meant to go
    w_lim = turn + W_CORRECTION
    w = max(-w_lim, min(w_lim, w))
    return v, w, math.hypot(ex, ey)
