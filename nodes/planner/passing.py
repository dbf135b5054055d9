"""Robots that pass each other: a reciprocal layer over any planner's command (pure).

Potential fields among robots that each treat the others as obstacles lock up: sixteen
ROSbots sent across a ring all meet in the middle, where every robot's goal pull is
cancelled by the others' repulsion (docs/planners.md, "Fleets: robots that pass each
other"). This layer keeps the planner's command as the robot's *preferred velocity* and
changes it only as much as the robots around need, the way ORCA does:

1. **Preferred velocity.** The planner's heading ``theta*`` (eq. 3, or its planned
   heading) at the speed it asks for when aligned (eq. 5 with no heading error, or its
   planned speed).
2. **Keep right** (the passing convention of road traffic and of COLREGs rule 14, "each
   shall alter her course to starboard"): when another robot lies ahead, within
   :attr:`PassingParams.ahead_deg` of the preferred direction and closing, the preferred
   velocity turns right by :attr:`PassingParams.keep_right_deg`. Every robot doing the same
   turns a crowd in the middle into a roundabout, where ORCA alone may leave a symmetric
   crowd standing (every velocity the same distance from every preferred one).
3. **ORCA** (van den Berg, Guy, Lin, Manocha, "Reciprocal n-body collision avoidance",
   ISRR 2009, Sec. 5): one half-plane of permitted velocities per neighbour, each robot
   taking half of the avoidance, and the velocity closest to the preferred one inside them
   all (RVO2's linear programs, through ``pyrvo``). The neighbours are the run's obstacle
   tracks (``Objects``) within :attr:`PassingParams.range_m`: other robots (and people)
   with their velocities, as a fleet sharing its poses on the bus gives them (in
   simulation: the LiDAR node's ground truth, ``--objects truth``; on robots: the tracker's
   tracks from the robot's own LiDAR, ``--objects tracker``).
4. **A differential-drive robot follows it** (Alonso-Mora, Breitenmoser, Rufli, Beardsley,
   Siegwart, "Optimal reciprocal collision avoidance for multiple non-holonomic robots",
   DARS 2010): the robot cannot take a sideways velocity at once, so its disc is enlarged
   by the tracking error it allows (:attr:`PassingParams.margin_m`) and it turns to the
   ORCA velocity's heading with the planner's own heading controller while eq. 5 scales
   its speed by the heading error (none beyond 30 deg: it turns first).

Without a neighbour in range the planner's ``(v, w)`` pass through untouched, so a robot
alone — and every one-robot run — is bit for bit the planner's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from common.robot import FOOTPRINT_RADIUS_M
from nodes.planner.field import APFParams, speed_ref, turn_rate, wrap_angle

MODES = ("off", "orca")
EXTERNAL_MAX_SPEED_M_S = 100.0   # [m/s] a neighbour's cap in RVO2: its velocity is given


@dataclass(frozen=True)
class PassingParams:
    """The passing layer's settings (module doc)."""

    mode: str = "off"              # off | orca
    range_m: float = 3.0           # [m] neighbours within this distance (centre to centre)
    max_neighbors: int = 10        # [-] nearest ones in ORCA
    max_agent_radius_m: float = 1.0  # [m] a track wider than this is not an agent (a wall)
    time_horizon_s: float = 4.0    # [s] ORCA's tau: velocities safe for this long
    margin_m: float = 0.05         # [m] added to our disc: the tracking error allowed (NH-ORCA)
    keep_right_deg: float = 30.0   # [deg] the turn to the right when someone is ahead, closing
    ahead_deg: float = 45.0        # [deg] half-angle of "ahead" about the preferred direction
    step_s: float = 0.1            # [s] ORCA's step: the control period (10 Hz scans)


class Passing:
    """The layer of one robot (module doc); :meth:`adjust` once per control cycle."""

    def __init__(self, params: PassingParams | None = None):
        self.params = params or PassingParams()

    def neighbours(self, x: float, y: float, tracks) -> list:
        """The agents among ``tracks`` within ``range_m`` of (x, y), nearest first, at most
        ``max_neighbors``. An agent is a track whose circumscribed disc
        (:func:`agent_radius`) is at most ``max_agent_radius_m`` (a robot, a person, a small
        obstacle); a wall or a road's car is left to the planner."""
        prm = self.params
        near = sorted(((math.hypot(t.x - x, t.y - y), k, t) for k, t in enumerate(tracks)
                       if agent_radius(t) <= prm.max_agent_radius_m), key=lambda e: (e[0], e[1]))
        return [t for d, _, t in near if d <= prm.range_m][: prm.max_neighbors]

    def adjust(self, x: float, y: float, yaw: float, v_now: float, theta_ref: float,
               v_des: float, v: float, w: float, tracks, apf: APFParams) -> tuple[float, float]:
        """The command ``(v, w)`` after the layer; the planner's own when nobody is near.

        ``theta_ref`` [rad] and ``v_des`` [m/s]: the planner's heading and its speed when
        aligned (the preferred velocity); ``v_now`` [m/s]: the robot's speed along its
        heading (odometry).
        """
        prm = self.params
        if prm.mode == "off":
            return v, w
        near = self.neighbours(x, y, tracks)
        if not near:
            return v, w
        heading = theta_ref
        if self._someone_ahead(x, y, v_des, theta_ref, near):
            heading = theta_ref - math.radians(prm.keep_right_deg)
        pref = (v_des * math.cos(heading), v_des * math.sin(heading))
        ux, uy = _orca(x, y, (v_now * math.cos(yaw), v_now * math.sin(yaw)), pref, near,
                       FOOTPRINT_RADIUS_M + prm.margin_m, max(apf.v_max, v_des), prm)
        speed = math.hypot(ux, uy)
        if speed < 1e-6:                         # stand: turn to where the planner points
            return 0.0, turn_rate(heading, yaw, apf)
        theta = math.atan2(uy, ux)
        return speed_ref(speed, wrap_angle(theta - yaw), apf), turn_rate(theta, yaw, apf)

    def _someone_ahead(self, x: float, y: float, v_des: float, theta: float, near) -> bool:
        """A neighbour within ``ahead_deg`` of ``theta`` whose distance shrinks."""
        half = math.radians(self.params.ahead_deg)
        cx, cy = math.cos(theta), math.sin(theta)
        for t in near:
            rx, ry = t.x - x, t.y - y
            bearing = abs(wrap_angle(math.atan2(ry, rx) - theta))
            closing = (t.vx - v_des * cx) * rx + (t.vy - v_des * cy) * ry   # d|r|^2/dt / 2
            if bearing <= half and closing < 0.0:
                return True
        return False


def agent_radius(track) -> float:
    """[m] the disc ORCA gives a track: its box's circumscribed circle (a person's disc comes
    as a square of its diameter: 1.41 x its radius, on the safe side); a track without a
    size is a ROSbot."""
    if track.length > 0 or track.width > 0:
        return 0.5 * math.hypot(track.length, track.width)
    return FOOTPRINT_RADIUS_M


def _orca(x: float, y: float, vel, pref, near, radius: float, max_speed: float,
          prm: PassingParams) -> tuple[float, float]:
    """ORCA's new velocity of the robot at (x, y) among ``near`` (RVO2 one step, ``pyrvo``)."""
    import pyrvo  # the layer's one dependency, loaded only where a fleet runs

    sim = pyrvo.RVOSimulator()
    sim.set_time_step(prm.step_s)
    tau = prm.time_horizon_s
    sim.add_agent((x, y), prm.range_m, prm.max_neighbors, tau, tau, radius, max_speed,
                  (float(vel[0]), float(vel[1])))
    sim.set_agent_pref_velocity(0, (float(pref[0]), float(pref[1])))
    for k, t in enumerate(near, start=1):
        sim.add_agent((float(t.x), float(t.y)), prm.range_m, prm.max_neighbors, tau, tau,
                      agent_radius(t),
                      EXTERNAL_MAX_SPEED_M_S, (float(t.vx), float(t.vy)))
        sim.set_agent_pref_velocity(k, (float(t.vx), float(t.vy)))
    sim.do_step()
    return sim.get_agent_velocity(0).to_tuple()
