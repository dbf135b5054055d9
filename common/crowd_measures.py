"""Crowd-navigation measures of each robot, fed one control step at a time. Pure.

The robot is its footprint box (``common.robot`` BODY_LENGTH_M along its heading x
BODY_WIDTH_M across), a person a disc. Per robot (``CrowdMeter.results``):

- **minimum separation** [m]: the closest approach of the footprint to a person's disc or
  another robot's footprint (0 = contact; CrowdNav's "closest distance", Chen et al. 2019);
- **discomfort time** [s]: time with a person within ``DISCOMFORT_M`` = 0.2 m of the
  footprint (CrowdNav's discomfort distance); a step counts as a whole when it ends so;
- **personal-space intrusions** [-]: entries of a person into ``PERSONAL_SPACE_M`` = 0.5 m of
  the footprint (arena-rosnav / SEANavBench's personal-space violations), a person already
  inside at the first step counted once;
- **path irregularity** [rad/m]: unnecessary turning per metre (Guzzi et al. 2013,
  "Human-friendly robot navigation in dynamic environments", ICRA; SocNavBench, Biswas et
  al. 2022): (total |heading change| - the turn a straight path needs, i.e. from the first
  heading to the bearing of the goal) / path length. Without a goal, the last position;
- **Hall's zones** [s, -]: per zone (intimate 0.45 m, personal 1.2 m, social 3.6 m of the
  footprint), the time someone was within it and the entries of people into it;
- **group-space intrusions** [-, s]: entries of the footprint into a ``[[groups]]``
  group's space while its members are together, and the time spent in one;
- **minimum time to collision** [s] over the run (inf: nobody ever closed in).

The last three's geometry and sources: :mod:`common.crowd_social`. A person of radius 0 (a
replayed person not in the scene) is not there for any measure.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from common.crowd_social import HALL_ZONES, group_gap, time_to_collision, together
from common.robot import BODY_LENGTH_M, BODY_WIDTH_M

DISCOMFORT_M = 0.2        # [m] CrowdNav's discomfort distance
PERSONAL_SPACE_M = 0.5    # [m] personal space (intrusions)
_HALF = np.array([BODY_LENGTH_M / 2, BODY_WIDTH_M / 2])
# [m] a footprint's circumradius: two footprints are at least their centres' distance less
# twice this apart (less a slack far above the rounding of either computation)
_REACH_M = 2 * math.hypot(BODY_LENGTH_M / 2, BODY_WIDTH_M / 2) + 1e-9


def box_corners(x: float, y: float, yaw: float) -> np.ndarray:
    """(4, 2) [m] corners of a footprint at (x, y) [m] heading yaw [rad], counter-clockwise."""
    c, s = math.cos(yaw), math.sin(yaw)
    local = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]]) * _HALF
    return np.column_stack([x + c * local[:, 0] - s * local[:, 1],
                            y + s * local[:, 0] + c * local[:, 1]])


def point_box_distance(pts: np.ndarray, x: float, y: float, yaw: float) -> np.ndarray:
    """(n,) [m] from each point (n, 2) to the footprint at (x, y, yaw); 0 inside."""
    pts = np.asarray(pts, float).reshape(-1, 2)
    c, s = math.cos(yaw), math.sin(yaw)
    rx, ry = pts[:, 0] - x, pts[:, 1] - y
    u, v = np.abs(c * rx + s * ry), np.abs(-s * rx + c * ry)
    return np.hypot(np.maximum(u - _HALF[0], 0.0), np.maximum(v - _HALF[1], 0.0))


def box_box_distance(a: tuple[float, float, float], b: tuple[float, float, float]) -> float:
    """[m] between two footprints (x, y, yaw); 0 when they touch or overlap."""
    ca, cb = box_corners(*a), box_corners(*b)
    if not _separated(ca, cb, (a[2], b[2])):
        return 0.0
    return float(min(point_box_distance(ca, *b).min(), point_box_distance(cb, *a).min()))


def _separated(ca: np.ndarray, cb: np.ndarray, yaws) -> bool:
    """True when an edge normal of either box separates the two corner sets."""
    for yaw in yaws:
        for axis in ((math.cos(yaw), math.sin(yaw)), (-math.sin(yaw), math.cos(yaw))):
            pa, pb = ca @ axis, cb @ axis
            if pa.max() < pb.min() or pb.max() < pa.min():
                return True
    return False


class _RobotGaps:
    """The robots' footprint distances of one step: a pair's distance computed once (it is
    symmetric, to the bit: the same axes tested, the same two minima taken) and only when it
    could lower a robot's minimum — a pair whose centres are farther apart than that minimum
    plus two circumradii cannot, so a fleet's step costs a few pairs, not every pair twice."""

    def __init__(self, robots: dict):
        self.poses = [tuple(float(v) for v in p) for p in robots.values()]
        self.index = {name: i for i, name in enumerate(robots)}
        xy = np.array([p[:2] for p in self.poses], float).reshape(-1, 2)
        self.centres = np.hypot(xy[:, None, 0] - xy[None, :, 0], xy[:, None, 1] - xy[None, :, 1])
        self._known: dict[tuple[int, int], float] = {}

    def closest(self, name: str, below: float) -> float:
        """min(``below``, robot ``name``'s footprint distance to every other robot) [m]."""
        i, best = self.index[name], below
        for j, centre in enumerate(self.centres[i]):
            if j == i or centre - _REACH_M >= best:
                continue
            pair = (i, j) if i < j else (j, i)
            d = self._known.get(pair)
            if d is None:
                d = self._known[pair] = box_box_distance(self.poses[pair[0]], self.poses[pair[1]])
            best = min(best, d)
        return best


def _wrap(a: float) -> float:
    """An angle [rad] into [-pi, pi)."""
    return (a + math.pi) % (2 * math.pi) - math.pi


@dataclass(frozen=True)
class CrowdMeasures:
    """One robot's measures (module doc); inf: nobody was ever there to measure against."""

    min_separation_m: float          # to anyone (person or robot) [m]
    min_person_separation_m: float   # to a person's disc [m]
    min_robot_separation_m: float    # to another robot's footprint [m]
    discomfort_s: float              # a person within DISCOMFORT_M [s]
    intrusions: int                  # entries into PERSONAL_SPACE_M [-]
    path_m: float                    # length of the path [m]
    rotation_rad: float              # total |heading change| [rad]
    irregularity_rad_per_m: float    # unnecessary turning per metre [rad/m]
    intimate_s: float = 0.0          # someone within 0.45 m [s] (Hall's intimate zone)
    personal_s: float = 0.0          # someone within 1.2 m [s]
    social_s: float = 0.0            # someone within 3.6 m [s]
    intimate_n: int = 0              # entries of people into the intimate zone [-]
    personal_n: int = 0              # ... the personal zone
    social_n: int = 0                # ... the social zone
    group_intrusions: int = 0        # entries into a group's space [-]
    group_s: float = 0.0             # time inside a group's space [s]
    min_ttc_s: float = math.inf      # least time to collision [s]


@dataclass
class _Track:
    poses: list = field(default_factory=list)     # (x, y, yaw)
    path_m: float = 0.0
    rotation_rad: float = 0.0
    person_min: float = math.inf
    robot_min: float = math.inf
    discomfort_s: float = 0.0
    intrusions: int = 0
    inside: np.ndarray | None = None              # (n,) bool: person in personal space
    zone_s: dict = field(default_factory=lambda: {name: 0.0 for name, _ in HALL_ZONES})
    zone_n: dict = field(default_factory=lambda: {name: 0 for name, _ in HALL_ZONES})
    zone_in: dict = field(default_factory=dict)   # zone -> (n,) bool: person inside
    group_n: int = 0
    group_s: float = 0.0
    group_in: np.ndarray | None = None            # (groups,) bool: footprint inside
    ttc: float = math.inf


def _entries(before: np.ndarray | None, inside: np.ndarray) -> int:
    """New members of ``inside`` since ``before`` (all of them at the first step)."""
    if before is None or len(before) != len(inside):
        before = np.zeros(len(inside), bool)
    return int((inside & ~before).sum())


class CrowdMeter:
    """Per-robot crowd measures; ``goals`` name -> (x, y) [m] for the irregularity;
    ``groups``: each group's members (indexes into the people's arrays)."""

    def __init__(self, goals: dict[str, tuple[float, float]] | None = None,
                 groups: tuple[tuple[int, ...], ...] = ()):
        self._goals = dict(goals or {})
        self._groups = [np.asarray(g, int) for g in groups]
        self._tracks: dict[str, _Track] = {}
        self._t: float | None = None
        self._xy: np.ndarray | None = None        # the people's last centres (velocities)

    def update(self, t_s: float, robots: dict[str, tuple[float, float, float]],
               people_xy: np.ndarray, people_radii: np.ndarray, active=None,
               people_v: np.ndarray | None = None) -> None:
        """One control step at time t_s [s]: robots' poses (x [m], y [m], yaw [rad]), people's
        centres (n, 2) [m], radii (n,) [m] (0: not in the scene) and velocities (n, 2) [m/s]
        (default: from their last centres); ``active``: the names measured this step
        (default all; the others are only there to be kept clear of, e.g. a robot at its goal)."""
        dt = 0.0 if self._t is None else t_s - self._t
        if dt < 0:
            raise ValueError(f"time went back: {t_s} s after {self._t} s")
        xy = np.asarray(people_xy, float).reshape(-1, 2)
        radii = np.asarray(people_radii, float).reshape(-1)
        if len(radii) != len(xy):
            raise ValueError(f"{len(xy)} people positions but {len(radii)} radii")
        if people_v is None:
            people_v = (xy - self._xy) / dt if dt > 0 and self._xy is not None and \
                len(self._xy) == len(xy) else np.zeros_like(xy)
        self._t, self._xy = t_s, xy
        here = radii > 0
        people = (xy[here], radii[here], np.asarray(people_v, float).reshape(-1, 2)[here])
        gaps = _RobotGaps(robots)
        for name, pose in robots.items():
            if active is None or name in active:
                self._robot(self._tracks.setdefault(name, _Track()), name, pose, gaps, dt,
                            people, xy, radii)

    def _robot(self, tr: _Track, name: str, pose, gaps: _RobotGaps, dt: float, people, all_xy,
               all_radii) -> None:
        """One robot's share of a step."""
        x, y, yaw = (float(v) for v in pose)
        v = (0.0, 0.0)
        if tr.poses:
            px, py, pyaw = tr.poses[-1]
            tr.path_m += math.hypot(x - px, y - py)
            tr.rotation_rad += abs(_wrap(yaw - pyaw))
            if dt > 0:
                v = ((x - px) / dt, (y - py) / dt)
        tr.poses.append((x, y, yaw))
        xy, radii, pv = people
        if len(all_xy):
            # every person keeps a slot (entries are per person), one not there never inside
            gap_all = np.full(len(all_xy), math.inf)
            here = all_radii > 0
            gap_all[here] = np.maximum(point_box_distance(all_xy[here], x, y, yaw)
                                       - all_radii[here], 0.0)
            if here.any():
                tr.person_min = min(tr.person_min, float(gap_all.min()))
                if gap_all.min() < DISCOMFORT_M:
                    tr.discomfort_s += dt
                tr.ttc = min(tr.ttc, time_to_collision((x, y), v, xy, pv, radii))
            inside = gap_all < PERSONAL_SPACE_M
            tr.intrusions += _entries(tr.inside, inside)
            tr.inside = inside
            for zone, reach in HALL_ZONES:
                within = gap_all < reach
                tr.zone_n[zone] += _entries(tr.zone_in.get(zone), within)
                tr.zone_in[zone] = within
                if within.any():
                    tr.zone_s[zone] += dt
        if self._groups:
            self._in_groups(tr, box_corners(x, y, yaw), all_xy, all_radii, dt)
        tr.robot_min = gaps.closest(name, tr.robot_min)

    def _in_groups(self, tr: _Track, corners: np.ndarray, xy: np.ndarray, radii: np.ndarray,
                   dt: float) -> None:
        """Entries into, and time in, a group's space (common/crowd_social.py)."""
        inside = np.array([together(xy[g], radii[g])
                           and group_gap(corners, xy[g], float(radii[g].mean())) <= 0.0
                           for g in self._groups], bool)
        tr.group_n += _entries(tr.group_in, inside)
        tr.group_in = inside
        if inside.any():
            tr.group_s += dt

    def results(self) -> dict[str, CrowdMeasures]:
        """name -> the robot's measures so far."""
        return {name: self._measures(name, tr) for name, tr in self._tracks.items()}

    def _measures(self, name: str, tr: _Track) -> CrowdMeasures:
        """One robot's :class:`CrowdMeasures`."""
        x0, y0, yaw0 = tr.poses[0]
        gx, gy = self._goals.get(name, tr.poses[-1][:2])
        needed = abs(_wrap(math.atan2(gy - y0, gx - x0) - yaw0)) \
            if math.hypot(gx - x0, gy - y0) > 1e-9 else 0.0
        irregular = max(tr.rotation_rad - needed, 0.0) / tr.path_m if tr.path_m > 1e-9 else 0.0
        return CrowdMeasures(min_separation_m=min(tr.person_min, tr.robot_min),
                             min_person_separation_m=tr.person_min,
                             min_robot_separation_m=tr.robot_min,
                             discomfort_s=tr.discomfort_s, intrusions=tr.intrusions,
                             path_m=tr.path_m, rotation_rad=tr.rotation_rad,
                             irregularity_rad_per_m=irregular,
                             **{f"{z}_s": tr.zone_s[z] for z, _ in HALL_ZONES},
                             **{f"{z}_n": tr.zone_n[z] for z, _ in HALL_ZONES},
                             group_intrusions=tr.group_n, group_s=tr.group_s,
                             min_ttc_s=tr.ttc)
