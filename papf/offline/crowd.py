"""Several robots and people offline: :func:`plan_crowd` (called by
:func:`papf.offline.run.simulate` for a world with ``[[robots]]`` or ``[[people]]``).

Every robot is the offline ROSbot of :mod:`papf.offline.plan` — its planner from the
registry (the robot's ``planner``, else the run's), its own LiDAR sim, the driver's command
gate and the unicycle of :class:`papf.offline.unicycle.Drive` — and all of them advance in
lockstep, one control period ``dt`` at a time:

1. every active robot scans and moves (:meth:`Drive.cycle`): its LiDAR sees the world's
   obstacles, the other robots' footprint boxes and the people's discs (cylinders
   ``PERSON_HEIGHT_M`` tall) where they stood at the start of the period;
2. the people take the same period (:class:`common.crowd.Crowd`), seeing the robots;
3. a person now overlapping a robot's footprint is a robot-person collision of that robot;
4. :class:`common.crowd_measures.CrowdMeter` takes the step.

A planner that reads obstacle tracks (``uses_objects``: ORCA, social force, IAPF) gets, before
each scan, the ground truth the stack's LiDAR gives with ``--objects truth``
(:func:`worlds.messages.truth_objects`: the people in the scene and the other robots within
the LiDAR's range, with their velocities). A person collision is split by who caused it
(:func:`common.crowd_social.collision_cause`). When the run is over, the same people walk the
same time again without the robots (same seed): their path and time to their goals against
the run's give the robot's effect on them (:func:`common.crowd_social.extension`).

Collisions (the footprint's clearance < 0, checked every 20 ms substep of the drive):
``wall`` (the world's obstacles, pybullet as ``papf plan``), ``robot`` (another robot's
footprint, at its pose of the period's start), ``person`` (a disc). A robot stops at its
outcome and stays where it is, an obstacle to the others. Robot ``i`` draws its LiDAR noise
and start jitter from seed ``seed + ROBOT_SEED_STRIDE * i`` (robot 0: the run's seed, as
``papf plan`` of that robot alone); the people from ``seed``. Same seed, same figures.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from common.crowd import Crowd
from common.crowd_measures import CrowdMeter, box_box_distance, point_box_distance
from common.crowd_social import collision_cause, extension
from common.drive import CommandGate, RosbotLimits
from common.quiet import import_quietly
from nodes.lidar_sim.core import LidarSim
from nodes.planner.passing import Passing, PassingParams
from nodes.planner.registry import make_planner
from nodes.planner.road import Track
from nodes.world_sim.physics import SimParams
from papf.offline.result import PlanResult
from papf.offline.unicycle import Drive, FootprintChecker, start_pose
from schemas.messages import Bodies
from worlds import World
from worlds.messages import truth_objects

p = import_quietly("pybullet")

ROBOT_SEED_STRIDE = 7919      # [-] seed offset between robots (a prime: no overlap in sweeps)
PERSON_HEIGHT_M = 1.7         # [m] a person's cylinder in the LiDAR's world
ROBOT_SEEN_HEIGHT_M = 0.3     # [m] another robot's box in the LiDAR's world (chassis to LiDAR)
COLLISION_KINDS = ("wall", "robot", "person")
OUTCOME_ORDER = ("collision", "failed", "stagnated", "timeout", "reached")  # the fleet's: worst


@dataclass
class RobotRun:
    """One robot of a crowd run: its drive's result and its crowd figures."""

    name: str
    planner: str
    result: PlanResult
    collisions: dict = field(default_factory=lambda: dict.fromkeys(COLLISION_KINDS, 0))
    measures: object = None       # common.crowd_measures.CrowdMeasures
    caused: dict = field(default_factory=lambda: {"robot": 0, "person": 0})  # person collisions
    effect: object = None         # common.crowd_social.Extension: the people's, of the run

    def summary(self) -> dict:
        """The robot's object of ``papf plan --json`` (``robots``)."""
        m, r = self.measures, self.result
        return {"name": self.name, "planner": self.planner, "outcome": r.outcome,
                "duration_s": round(r.duration_s, 6), "path_length_m": round(r.length_m, 6),
                "collisions": r.collisions, **{f"collisions_{k}": v
                                               for k, v in self.collisions.items()},
                **{f"collisions_person_by_{k}": v for k, v in self.caused.items()},
                "min_clearance_m": round(r.min_clearance_m, 6),
                "min_separation_m": _num(m.min_separation_m),
                "min_person_separation_m": _num(m.min_person_separation_m),
                "min_robot_separation_m": _num(m.min_robot_separation_m),
                "discomfort_s": round(m.discomfort_s, 6), "intrusions": m.intrusions,
                "path_irregularity_rad_per_m": round(m.irregularity_rad_per_m, 6),
                **{f"{z}_{u}": round(getattr(m, f"{z}_{u}"), 6) for z in HALL for u in "sn"},
                "group_intrusions": m.group_intrusions, "group_s": round(m.group_s, 6),
                "min_ttc_s": _num(m.min_ttc_s),
                **_effect_json(self.effect), "reason": r.reason}


HALL = ("intimate", "personal", "social")


def _effect_json(e) -> dict:
    """The people's path and time extension as JSON figures (None: nobody to compare)."""
    if e is None:
        return {}
    return {"people_compared": e.people, "people_held": e.held,
            "people_path_ext_m": _num(e.path_m), "people_time_ext_s": _num(e.time_s),
            "people_path_ext_pct": _num(e.path_pct), "people_time_ext_pct": _num(e.time_pct)}


@dataclass
class CrowdRun:
    """Everything of a crowd run: the robots, and the people's tracks."""

    robots: list[RobotRun]
    times: np.ndarray             # (T,) [s]
    people: np.ndarray            # (T, n, 2) [m]
    radii: np.ndarray             # (n,) [m] each body's, when in the scene
    shown: np.ndarray | None = None   # (T, n) [m] radius at each time: 0 = not in the scene


def _num(v: float):
    """A figure for JSON: rounded, None when infinite or nan (nobody to measure against)."""
    return round(v, 6) if math.isfinite(v) else None


class _Senses:
    """Robot ``i``'s LiDAR and clearance, with the others where they stood (module doc)."""

    def __init__(self, world: World, lidar, i: int, n_robots: int, radii: np.ndarray,
                 seed: int, checker: FootprintChecker):
        self.i, self.checker = i, checker
        self.lidar = LidarSim(world, lidar, seed)
        cid = self.lidar.cid
        sx, sy, _ = SimParams().chassis_size
        box = p.createCollisionShape(p.GEOM_BOX, halfExtents=[sx / 2, sy / 2,
                                                              ROBOT_SEEN_HEIGHT_M / 2],
                                     physicsClientId=cid)
        self.robot_bodies = [p.createMultiBody(0.0, box, basePosition=[0, 0, -10],
                                               physicsClientId=cid) for _ in range(n_robots)]
        self.person_bodies = []
        for r in radii:
            shape = p.createCollisionShape(p.GEOM_CYLINDER, radius=float(r),
                                           height=PERSON_HEIGHT_M, physicsClientId=cid)
            self.person_bodies.append(p.createMultiBody(0.0, shape, basePosition=[0, 0, -10],
                                                        physicsClientId=cid))
        self.poses: list[tuple[float, float, float]] = []
        self.people = np.zeros((0, 2))
        self.radii = radii
        self.here = np.zeros(0, bool)
        self._was_here = np.ones(len(radii), bool)   # every body placed on the first look
        self.kind = "wall"            # what the last clearance was closest to
        self.person = -1              # the person it was, if one

    def see(self, poses, people: np.ndarray, radii_now: np.ndarray | None = None) -> None:
        """The others' poses (x, y, yaw) and the people's centres (n, 2) [m] for this period;
        ``radii_now``: 0 for a person not in the scene (default: everybody is)."""
        self.poses, self.people = poses, people
        self.here = np.ones(len(people), bool) if radii_now is None else np.asarray(radii_now) > 0
        cid = self.lidar.cid
        for j, (body, (x, y, yaw)) in enumerate(zip(self.robot_bodies, poses, strict=True)):
            pos = [x, y, ROBOT_SEEN_HEIGHT_M / 2] if j != self.i else [0, 0, -10]
            p.resetBasePositionAndOrientation(body, pos, p.getQuaternionFromEuler([0, 0, yaw]),
                                              physicsClientId=cid)
        for k in np.flatnonzero(self.here | self._was_here):   # the absent stay parked
            pos = [float(people[k][0]), float(people[k][1]), PERSON_HEIGHT_M / 2] \
                if self.here[k] else [0, 0, -10]
            p.resetBasePositionAndOrientation(self.person_bodies[k], pos, [0, 0, 0, 1],
                                              physicsClientId=cid)
        self._was_here = self.here

    def scan(self, x, y, yaw, t_ns):
        """The robot's scan at pose (x [m], y [m], yaw [rad]) and sim time t_ns [ns]."""
        return self.lidar.scan(x, y, yaw, t_ns)

    def clearance(self, x: float, y: float, yaw: float, t_ns: int) -> float:
        """[m] to the nearest of walls, other robots and people; < 0: a collision."""
        best, self.kind = self.checker.clearance(x, y, yaw, t_ns), "wall"
        for j, pose in enumerate(self.poses):
            if j != self.i:
                d = box_box_distance((x, y, yaw), pose)
                d = d if d > 0 else -1e-9          # touching is a collision
                if d < best:
                    best, self.kind = d, "robot"
        if self.here.any():
            gaps = np.where(self.here, point_box_distance(self.people, x, y, yaw) - self.radii,
                            np.inf)
            k = int(gaps.argmin())
            if gaps[k] < best:
                best, self.kind, self.person = float(gaps[k]), "person", k
        return best

    def close(self) -> None:
        """Disconnect the LiDAR's pybullet client."""
        self.lidar.close()


def passing_for(world: World, mode: str | None) -> str:
    """The passing layer of a run: ``mode`` as given, else ``orca`` for a fleet of two or
    more robots and ``off`` otherwise (one robot keeps its planner's figures)."""
    if mode is not None:
        return mode
    return "orca" if len(world.robots) >= 2 else "off"


def plan_crowd(world: World, planner_name: str, sets: list[str], params_file, seed: int,
               max_time_s: float, dt: float, keep_states: bool = False,
               lidar=None, passing: str | None = None) -> PlanResult:
    """Every robot of ``world`` among its people to an outcome (module doc); the fleet's
    :class:`PlanResult` with the whole run in ``trace`` (a :class:`CrowdRun`).

    ``passing``: the planners' passing layer (:func:`passing_for`); on, each planner gets the
    other robots and the people as obstacle tracks (ground truth) every period."""
    mode = passing_for(world, passing)
    fleet = world.fleet
    crowd = Crowd(world.people, world, seed)
    radii = crowd.body_radii
    checker = FootprintChecker(world)
    senses, drives = [], []
    try:
        for i, spec in enumerate(fleet):
            rseed = seed + ROBOT_SEED_STRIDE * i
            own = replace(world, start=spec.start, goal=spec.goal,
                          tolerance=spec.tolerance)
            s = _Senses(world, lidar, i, len(fleet), radii, rseed, checker)
            senses.append(s)
            s.see([tuple(r.start) for r in fleet], crowd.positions, crowd.radii)
            planner = make_planner(spec.planner or planner_name, params_file, sets)
            if mode != "off":
                planner.passing = Passing(PassingParams(mode=mode, step_s=dt))
            drives.append(Drive(own, planner, spec.planner or planner_name, rseed,
                                start_pose(own, rseed), s.scan, s.clearance, max_time_s, dt,
                                CommandGate(RosbotLimits()), keep_states))
        run = _lockstep(world, fleet, drives, senses, crowd, dt)
        _people_effect(world, seed, crowd, run, dt)
    finally:
        for s in senses:
            s.close()
        checker.close()
    return _fleet_result(world, seed, run)


def _velocity(d) -> tuple[float, float]:
    """[m/s] a drive's world-frame velocity now."""
    return d.v * math.cos(d.yaw), d.v * math.sin(d.yaw)


def _bodies(world: World, fleet, drives, i: int, crowd: Crowd, t_ns: int) -> Bodies:
    """What the stack's driver would put on robot ``i``'s ``sim/bodies`` now."""
    xy, v, r = crowd.positions, crowd.velocities, crowd.radii
    others = [j for j in range(len(drives)) if j != i]
    return Bodies(stamp_ns=t_ns, robots=tuple(fleet[j].name or "robot" for j in others),
                  robot_x=tuple(drives[j].x for j in others),
                  robot_y=tuple(drives[j].y for j in others),
                  robot_yaw=tuple(drives[j].yaw for j in others),
                  person_x=tuple(map(float, xy[:, 0])), person_y=tuple(map(float, xy[:, 1])),
                  person_radius=tuple(map(float, r)),
                  robot_vx=tuple(_velocity(drives[j])[0] for j in others),
                  robot_vy=tuple(_velocity(drives[j])[1] for j in others),
                  person_vx=tuple(map(float, v[:, 0])), person_vy=tuple(map(float, v[:, 1])))


def _give_objects(world: World, fleet, drives, i: int, crowd: Crowd, lidar_range: float) -> None:
    """Robot ``i``'s planner gets the ground-truth tracks (module doc), if it reads them or
    its passing layer (nodes.planner.passing) does."""
    d = drives[i]
    if not d.planner.strategy.uses_objects and d.planner.passing is None:
        return
    objects = truth_objects(world, d.t, (d.x, d.y), lidar_range,
                            _bodies(world, fleet, drives, i, crowd, d.t))
    d.planner.set_objects(Track(o.x, o.y, o.yaw, o.vx, o.vy, o.length, o.width, o.id)
                          for o in objects.tracks)


class _Tally:
    """Each robot's collisions by kind, and its person collisions by who caused them."""

    def __init__(self, n: int):
        self.kinds = [dict.fromkeys(COLLISION_KINDS, 0) for _ in range(n)]
        self.caused = [{"robot": 0, "person": 0} for _ in range(n)]

    def person(self, i: int, d, crowd: Crowd, k: int) -> None:
        """Robot ``i`` (drive ``d``) touched person ``k``."""
        self.kinds[i]["person"] += 1
        self.caused[i][collision_cause((d.x, d.y), _velocity(d), crowd.positions[k],
                                       crowd.velocities[k])] += 1


def _lockstep(world, fleet, drives, senses, crowd, dt) -> CrowdRun:
    """Advance robots and people together until every robot has its outcome."""
    tally = _Tally(len(drives))
    meter = CrowdMeter({spec.name or "robot": spec.goal for spec in fleet},
                       tuple(g.members for g in world.groups))
    names = [spec.name or "robot" for spec in fleet]
    lidar_range = senses[0].lidar.params.range_max if senses else 0.0

    def poses():
        return [(d.x, d.y, d.yaw) for d in drives]

    meter.update(0.0, dict(zip(names, poses(), strict=True)), crowd.positions, crowd.radii,
                 people_v=crowd.velocities)
    times, tracks, shown, t = [0.0], [crowd.positions], [crowd.radii], 0.0
    while any(not d.outcome for d in drives):
        now, people, radii_now = poses(), crowd.positions, crowd.radii
        active = [i for i, d in enumerate(drives) if not d.outcome]
        for i in active:
            senses[i].see(now, people, radii_now)
            _give_objects(world, fleet, drives, i, crowd, lidar_range)
            drives[i].cycle()
            if drives[i].outcome == "collision":
                if senses[i].kind == "person":
                    tally.person(i, drives[i], crowd, senses[i].person)
                else:
                    tally.kinds[i][senses[i].kind] += 1
        crowd.step(dt, [(d.x, d.y, *_velocity(d)) if not d.outcome else (d.x, d.y, 0.0, 0.0)
                        for d in drives])
        t += dt
        people, radii_now = crowd.positions, crowd.radii
        for i in active:
            _walked_into(drives[i], i, crowd, tally)
        meter.update(t, dict(zip(names, poses(), strict=True)), people, radii_now,
                     active={names[i] for i in active}, people_v=crowd.velocities)
        times.append(t)
        tracks.append(people)
        shown.append(radii_now)
    measures = meter.results()
    robots = [RobotRun(name=names[i], planner=d.name, result=d.result(),
                       collisions=tally.kinds[i], caused=tally.caused[i],
                       measures=measures[names[i]])
              for i, d in enumerate(drives)]
    return CrowdRun(robots=robots, times=np.array(times),
                    people=np.array(tracks).reshape(len(times), -1, 2), radii=crowd.body_radii,
                    shown=np.array(shown).reshape(len(times), -1))


def _walked_into(d, i: int, crowd: Crowd, tally: _Tally) -> None:
    """A person who walked into robot ``i``'s footprint: a collision (who caused it: the
    velocities decide, as for any other)."""
    here = crowd.radii > 0
    if d.outcome or not here.any():
        return
    gaps = np.where(here, point_box_distance(crowd.positions, d.x, d.y, d.yaw) - crowd.radii,
                    np.inf)
    k = int(gaps.argmin())
    d.min_clear = min(d.min_clear, float(gaps[k]))
    if gaps[k] < 0:
        d.collisions += 1
        tally.person(i, d, crowd, k)
        d.outcome, d.t_end = "collision", d.t
        d.reason = f"a person walked into the footprint at ({d.x:.2f}, {d.y:.2f})"


def _people_effect(world: World, seed: int, crowd: Crowd, run: CrowdRun, dt: float) -> None:
    """The reacting people's walk without the robots, the same time (module doc): each
    robot's ``effect`` (the same people for all: the fleet's effect)."""
    if not world.people:
        return
    alone = Crowd(world.people, world, seed)
    for _ in range(len(run.times) - 1):
        alone.step(dt, [])
    effect = extension(crowd.first_goal_s(), crowd.walked_to_goal(), alone.first_goal_s(),
                       alone.walked_to_goal())
    for r in run.robots:
        r.effect = effect


def _truth_tracks(i: int, drives, crowd) -> list[Track]:
    """What robot ``i`` is told of the others at the period's start: every other robot's
    chassis box and velocity, every person's disc and velocity (as ``--objects truth``)."""
    sx, sy, _ = SimParams().chassis_size
    tracks = [Track(d.x, d.y, d.yaw, *((0.0, 0.0) if d.outcome else
                                       (d.v * math.cos(d.yaw), d.v * math.sin(d.yaw))), sx, sy, j)
              for j, d in enumerate(drives) if j != i]
    vel = crowd.velocities
    for k, ((x, y), r) in enumerate(zip(crowd.positions, crowd.radii, strict=True)):
        tracks.append(Track(float(x), float(y), 0.0, float(vel[k][0]), float(vel[k][1]),
                            2 * float(r), 2 * float(r), len(drives) + k))
    return tracks


def _fleet_result(world: World, seed: int, run: CrowdRun) -> PlanResult:
    """The fleet as one PlanResult: its worst outcome, the first robot's path, the sums."""
    results = [r.result for r in run.robots]
    worst = min(results, key=lambda r: OUTCOME_ORDER.index(r.outcome)
                if r.outcome in OUTCOME_ORDER else 0)
    first = results[0]
    names = {r.planner for r in results}
    return PlanResult(world=world.name, planner=", ".join(sorted(names)), seed=seed,
                      outcome=worst.outcome, reason=worst.reason if len(results) == 1 else
                      "; ".join(f"{r.name}: {r.result.outcome}" for r in run.robots),
                      path=first.path, times=first.times, headings=first.headings,
                      duration_s=max(r.duration_s for r in results),
                      sim_time_s=max(r.sim_time_s for r in results),
                      min_clearance_m=min(r.min_clearance_m for r in results),
                      collisions=sum(r.collisions for r in results), motion="crowd",
                      cycles=sum(r.cycles for r in results),
                      states=first.states, trace=run,
                      crowd={"people": int(run.radii.size),
                             "robots": [r.summary() for r in run.robots]})
