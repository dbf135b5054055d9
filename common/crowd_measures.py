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
  heading to the bearing of the goal) / path length. Without a goal, the last position.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from common.robot import BODY_LENGTH_M, BODY_WIDTH_M

DISCOMFORT_M = 0.2        # [m] CrowdNav's discomfort distance
PERSONAL_SPACE_M = 0.5    # [m] personal space (intrusions)
_HALF = np.array([BODY_LENGTH_M / 2, BODY_WIDTH_M / 2])


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


class CrowdMeter:
    """Per-robot crowd measures; ``goals`` name -> (x, y) [m] for the irregularity."""

    def __init__(self, goals: dict[str, tuple[float, float]] | None = None):
        self._goals = dict(goals or {})
        self._tracks: dict[str, _Track] = {}
        self._t: float | None = None

    def update(self, t_s: float, robots: dict[str, tuple[float, float, float]],
               people_xy: np.ndarray, people_radii: np.ndarray) -> None:
        """One control step at time t_s [s]: robots' poses (x [m], y [m], yaw [rad]), people's
        centres (n, 2) [m] and radii (n,) [m]."""
        dt = 0.0 if self._t is None else t_s - self._t
        if dt < 0:
            raise ValueError(f"time went back: {t_s} s after {self._t} s")
        self._t = t_s
        xy = np.asarray(people_xy, float).reshape(-1, 2)
        radii = np.asarray(people_radii, float).reshape(-1)
        if len(radii) != len(xy):
            raise ValueError(f"{len(xy)} people positions but {len(radii)} radii")
        for name, pose in robots.items():
            tr = self._tracks.setdefault(name, _Track())
            x, y, yaw = (float(v) for v in pose)
            if tr.poses:
                px, py, pyaw = tr.poses[-1]
                tr.path_m += math.hypot(x - px, y - py)
                tr.rotation_rad += abs(_wrap(yaw - pyaw))
            tr.poses.append((x, y, yaw))
            if len(xy):
                gap = np.maximum(point_box_distance(xy, x, y, yaw) - radii, 0.0)
                tr.person_min = min(tr.person_min, float(gap.min()))
                if gap.min() < DISCOMFORT_M:
                    tr.discomfort_s += dt
                inside = gap < PERSONAL_SPACE_M
                before = tr.inside if tr.inside is not None and len(tr.inside) == len(inside) \
                    else np.zeros(len(inside), bool)
                tr.intrusions += int((inside & ~before).sum())
                tr.inside = inside
            for other, opose in robots.items():
                if other != name:
                    tr.robot_min = min(tr.robot_min, box_box_distance((x, y, yaw),
                                                                      tuple(opose)))

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
                             irregularity_rad_per_m=irregular)
