"""People who react: a world's ``[[people]]`` walked with ORCA or the social-force model.

Pure (no zenoh), deterministic for a seed. ``model = "orca"`` people are agents of an
RVO2 simulator (``pyrvo``: van den Berg et al. 2011, "Reciprocal n-body collision
avoidance"); ``model = "social_force"`` people are pedestrians of ``pysocialforce``
(Helbing & Molnár 1995, Moussaïd et al. 2010). A world may mix both: each group is
simulated by its library and sees the other group, the robots (discs of
``common.robot.FOOTPRINT_RADIUS_M``) and the world's moving obstacles (discs of their
reach) as agents whose velocity is given, not chosen. Static obstacles (boxes, walls,
cylinders, maps' wall rectangles) are ORCA polygons and social-force wall segments.

A person walks its route (docs/worlds.md ``[[people]]``): the next waypoint when within its
own radius of the current one; after the last, the first again if ``loop``, else it has
arrived and stands still. The seed draws a tiny perturbation of each preferred velocity
(at most 0.1 mm/s, as RVO2's examples do) that breaks perfect symmetries (two people
exactly head-on); same seed, same inputs -> the same positions bit for bit.

Three more kinds of people share the world, none stepped by a model:

- **standing** people (``speed = 0``, or no goal and no waypoints) stay at their start: to
  both models they are agents whose velocity is given (zero), as the robots are;
- **replayed** people (``[[people_replay]]``, :mod:`worlds.people_replay`) are where their
  recording says at every instant (linear between rows) and do not react; they follow the
  ``[[people]]`` in every list (:attr:`Crowd.positions`, ...). One not in the scene has
  radius 0 (:attr:`Crowd.radii`; :attr:`Crowd.body_radii` is its radius when there) and,
  to the models, stands far away;
- **walking groups** (``[[groups]]``): each member walks its own route at the group's pace
  (the slowest member's preferred speed) and is drawn back toward the members' centre of
  mass when farther from it than ``(N - 1) / 2`` m - the coherence of Moussaïd et al.
  2010 ("The walking behaviour of pedestrian social groups and its impact on crowd
  dynamics", PLoS ONE 5(4), eq. 5: a unit force toward the centre of mass beyond that
  threshold), here a preferred-velocity term of :data:`GROUP_COHESION_M_S`. A member held
  up by the robot so holds up the others, and the group walks past side by side.
"""

from __future__ import annotations

import logging
import math
import sys
from collections.abc import Sequence

import numpy as np

from common.robot import FOOTPRINT_RADIUS_M

# ORCA agent parameters: CrowdNav's ORCA policy (Chen et al. 2019, crowd_sim/policy/orca.py)
ORCA_NEIGHBOR_DIST_M = 10.0    # [m] neighbours considered
ORCA_MAX_NEIGHBORS = 10        # [-]
ORCA_TIME_HORIZON_S = 5.0      # [s] against other agents
ORCA_TIME_HORIZON_OBST_S = 5.0  # [s] against obstacles
EXTERNAL_MAX_SPEED_M_S = 100.0  # [m/s] an external agent's cap in RVO2 (its velocity is given)
PERTURB_M_S = 1e-4             # [m/s] largest random perturbation of a preferred velocity
SF_CARROT_M = 1.0              # [m] pysocialforce stops 0.5 m short of its goal: aim this far
SF_SPEED_MULTIPLIER = 1.3      # [-] pysocialforce's max_speed_multiplier (its default)
ROUND_SIDES = 16               # [-] a cylinder becomes a circumscribed 16-gon
ORCA_SAFETY_M = 0.01           # [m] added to an ORCA agent's radius (CrowdNav's ORCA does)
# [m] added to a given-velocity agent's radius in ORCA: RVO2 assumes every agent takes half
# of the avoiding, a robot or another model's person does not
ORCA_EXTERNAL_MARGIN_M = 0.05
SF_WALL_STEP_M = 0.1           # [m] spacing of a wall's sample points (pysocialforce's 10/m)
GROUP_COHESION_M_S = 0.3       # [m/s] a group member's pull toward the members' centre (beyond
                               # (N - 1)/2 m; Moussaïd et al. 2010 give the force's direction
                               # and threshold, this size is ours: a step a third of a walk)
AWAY_M = 1.0e5                 # [m] where the models see a replayed person not in the scene


def obstacle_polygons(world) -> list[np.ndarray]:
    """The static obstacles' footprints as counter-clockwise polygons ((k, 2) [m])."""
    polys = []
    for ob in world.obstacles:
        if ob.moving:
            continue
        for s in ob.model.solids(ob):
            cx, cy = s.center[0], s.center[1]
            if s.form == "cube":
                c, sn = math.cos(s.yaw), math.sin(s.yaw)
                hx, hy = s.size[0] / 2, s.size[1] / 2
                pts = [(cx + c * dx - sn * dy, cy + sn * dx + c * dy)
                       for dx, dy in ((-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy))]
            else:  # cylinder, sphere: circumscribed polygon (never smaller)
                r = s.size[0] / 2 / math.cos(math.pi / ROUND_SIDES)
                a = np.arange(ROUND_SIDES) * (2 * math.pi / ROUND_SIDES)
                pts = list(zip(cx + r * np.cos(a), cy + r * np.sin(a), strict=True))
            polys.append(np.asarray(pts, float))
    return polys


class Crowd:
    """The people of a world, stepped with their models (module doc)."""

    def __init__(self, people: Sequence, world, seed: int, replay: bool = True):
        self._people = tuple(people)
        self._world = world
        self._rng = np.random.default_rng(seed)
        n = len(self._people)
        self._replay = tuple(world.replayed) if replay else ()
        self._replay_r = np.array([spec.radius for spec in world.people_replay
                                   for _ in spec.tracks] if replay else [], float)
        m = len(self._replay)
        self._pos = np.zeros((n + m, 2))
        self._pos[:n] = np.array([p.start for p in self._people], float).reshape(n, 2)
        self._vel = np.zeros((n + m, 2))
        self._radii = np.concatenate([np.array([p.radius for p in self._people], float)
                                      .reshape(n), self._replay_r])
        self._present = np.ones(n + m, bool)
        self._speed = np.array([p.speed for p in self._people], float).reshape(n)
        self._leg = np.zeros(n, int)           # index of the waypoint walked to
        self._standing = np.array([p.standing for p in self._people], bool).reshape(n)
        self._arrived = self._standing.copy()
        self._walked = np.zeros(n)             # [m] path each has walked
        self._first_goal_s = np.full(n, math.nan)   # [s] when each reached its first route point
        self._walked_goal = np.full(n, math.nan)    # [m] its path then
        self._t = 0.0                          # [s] since the start (moving obstacles' clock)
        self._moving = [ob for ob in world.obstacles if ob.moving]
        walking = [i for i, p in enumerate(self._people) if not p.standing]
        self._orca = np.array([i for i in walking if self._people[i].model == "orca"], int)
        self._sf = np.array([i for i in walking if self._people[i].model != "orca"], int)
        self._still = np.array([i for i, p in enumerate(self._people) if p.standing], int)
        self._groups = [np.array(g.members, int) for g in getattr(world, "groups", ())
                        if max(g.members) < n and not g.standing(self._people)]
        for g in self._groups:                 # the group's pace: its slowest member's
            self._speed[g] = self._speed[g].min()
        self._polys = obstacle_polygons(world)
        self._rvo = None
        self._sim = None
        self._n_ext = None
        self._spans = None                    # (m, 2) [s] each replayed person's first, last row
        self._present[n:] = True              # every replayed person placed on the first call
        self._place_replayed()

    # -- read-outs ------------------------------------------------------------------------
    @property
    def positions(self) -> np.ndarray:
        """(n, 2) [m] where each person stands."""
        return self._pos.copy()

    @property
    def velocities(self) -> np.ndarray:
        """(n, 2) [m/s] each person's velocity."""
        return self._vel.copy()

    @property
    def radii(self) -> np.ndarray:
        """(n,) [m] each person's body radius now; 0 for a replayed person not in the scene."""
        return np.where(self._present, self._radii, 0.0)

    @property
    def body_radii(self) -> np.ndarray:
        """(n,) [m] each person's body radius when in the scene."""
        return self._radii.copy()

    @property
    def present(self) -> np.ndarray:
        """(n,) bool: in the scene now (only a replayed person may not be)."""
        return self._present.copy()

    @property
    def reacting(self) -> int:
        """How many of the people are ``[[people]]`` (the rest are replayed)."""
        return len(self._people)

    @property
    def time_s(self) -> float:
        """[s] since the start."""
        return self._t

    def arrived(self) -> np.ndarray:
        """(n,) bool: reached its goal (or last waypoint, not looping); standing people have."""
        return self._arrived.copy()

    def walked(self) -> np.ndarray:
        """(k,) [m] the path each of the ``[[people]]`` has walked so far."""
        return self._walked.copy()

    def first_goal_s(self) -> np.ndarray:
        """(k,) [s] when each of the ``[[people]]`` reached its goal (its first waypoint); nan:
        not yet, or standing."""
        return self._first_goal_s.copy()

    def walked_to_goal(self) -> np.ndarray:
        """(k,) [m] the path each of the ``[[people]]`` had walked when it reached its goal
        (its first waypoint); nan: not yet, or standing."""
        return self._walked_goal.copy()

    # -- stepping -------------------------------------------------------------------------
    def step(self, dt_s: float, robots: Sequence[tuple[float, float, float, float]]) -> None:
        """Advance dt_s [s]; robots = (x, y, vx, vy) [m, m/s] of every robot, seen as discs
        of common.robot's circumscribed footprint radius (people avoid them)."""
        if not math.isfinite(dt_s) or dt_s <= 0:
            raise ValueError(f"dt_s must be a positive number of seconds, got {dt_s!r}")
        if not len(self._people):
            self._t += dt_s
            self._place_replayed()
            return
        self._advance_legs()
        ext = self._externals(robots)          # (m, 5): x, y, vx, vy, radius
        pref = self._preferred()               # (n, 2) [m/s]
        new_pos, new_vel = self._pos.copy(), self._vel.copy()
        if self._orca.size:
            p, v = self._step_orca(dt_s, ext, pref)
            new_pos[self._orca], new_vel[self._orca] = p, v
        if self._sf.size:
            p, v = self._step_sf(dt_s, ext, pref)
            new_pos[self._sf], new_vel[self._sf] = p, v
        n = len(self._people)
        self._walked += np.hypot(*(new_pos[:n] - self._pos[:n]).T)
        self._pos, self._vel = new_pos, new_vel
        self._t += dt_s
        self._place_replayed()
        self._advance_legs()

    def _place_replayed(self) -> None:
        """The replayed people where their recording has them at the current time."""
        from worlds.people_replay import replay_state

        n = len(self._people)
        t = round(self._t, 9)           # the sum of steps, to the ns: 200 x 0.02 s is 4 s
        if self._spans is None:
            self._spans = np.array([(tr.first_s, tr.last_s) for tr in self._replay],
                                   float).reshape(-1, 2)
        due = (self._spans[:, 0] <= t) & (t <= self._spans[:, 1])
        # the people in the scene now, and those who were a step ago (to leave it)
        for k in np.flatnonzero(due | self._present[n:]):
            track = self._replay[k]
            state = replay_state(track, t)
            self._present[n + k] = state is not None
            if state is None:       # held at the nearest row, not moving (radius 0 says gone)
                self._pos[n + k] = track.xy[0] if t < track.first_s else track.xy[-1]
                self._vel[n + k] = 0.0
            else:
                self._pos[n + k], self._vel[n + k] = state[:2], state[2:]

    def _advance_legs(self) -> None:
        """Next waypoint for whoever is within its radius of the current one."""
        for i, p in enumerate(self._people):
            while not self._arrived[i]:
                wx, wy = p.route[self._leg[i]]
                if math.hypot(wx - self._pos[i, 0], wy - self._pos[i, 1]) > self._radii[i]:
                    break
                if self._leg[i] == 0 and math.isnan(self._first_goal_s[i]):
                    self._first_goal_s[i], self._walked_goal[i] = self._t, self._walked[i]
                if self._leg[i] + 1 < len(p.route):
                    self._leg[i] += 1
                elif p.loop and len(p.route) > 1:
                    self._leg[i] = 0
                    break
                else:
                    self._arrived[i] = True

    def _preferred(self) -> np.ndarray:
        """(n, 2) [m/s] toward the current waypoint at the preferred speed (0 once arrived),
        plus the seeded perturbation."""
        n = len(self._people)
        target = np.array([p.route[k] if p.route else p.start
                           for p, k in zip(self._people, self._leg, strict=True)], float)
        d = target.reshape(n, 2) - self._pos[:n]
        dist = np.hypot(d[:, 0], d[:, 1])
        unit = d / np.maximum(dist, 1e-12)[:, None]
        pref = unit * self._speed[:, None]
        pref[self._arrived] = 0.0
        for g in self._groups:                 # coherence (module doc)
            centre = self._pos[g].mean(axis=0)
            off = centre - self._pos[g]
            far = np.hypot(off[:, 0], off[:, 1])
            pull = far > (len(g) - 1) / 2
            pref[g[pull]] += off[pull] / far[pull][:, None] * GROUP_COHESION_M_S
        angle = self._rng.uniform(0.0, 2 * math.pi, len(self._people))
        size = self._rng.uniform(0.0, PERTURB_M_S, len(self._people))
        return pref + np.column_stack([np.cos(angle), np.sin(angle)]) * size[:, None]

    def _externals(self, robots) -> np.ndarray:
        """(m, 5) the agents whose velocity is given: robots, moving obstacles, then the
        standing people and the replayed ones (far away while not in the scene)."""
        rows = [(float(x), float(y), float(vx), float(vy), FOOTPRINT_RADIUS_M)
                for x, y, vx, vy in robots]
        for ob in self._moving:
            s = ob.state_at(self._t)
            rows.append((s.x, s.y, s.vx, s.vy, ob.model.reach(ob)))
        n_given = len(rows)
        if self._n_ext is None:
            self._n_ext = n_given
        elif n_given != self._n_ext:
            raise ValueError(f"{len(robots)} robots given; this crowd was first stepped with "
                             f"{self._n_ext - len(self._moving)} (their number is fixed)")
        n = len(self._people)
        fixed = np.concatenate([self._still, np.arange(n, n + len(self._replay))]).astype(int)
        people = self._others_rows(fixed)
        gone = ~self._present[fixed]
        people[gone, 0] = AWAY_M + 10.0 * np.arange(int(gone.sum()))
        people[gone, 1] = AWAY_M
        return np.concatenate([np.array(rows, float).reshape(n_given, 5), people])

    def _step_orca(self, dt: float, ext: np.ndarray, pref: np.ndarray):
        """The ORCA group's new positions and velocities (RVO2 one step)."""
        import pyrvo

        own = self._orca
        others = np.concatenate([ext, self._others_rows(self._sf)])
        if self._rvo is None:
            sim = pyrvo.RVOSimulator()
            sim.set_time_step(dt)
            for i in own:
                sim.add_agent(tuple(self._pos[i]), ORCA_NEIGHBOR_DIST_M, ORCA_MAX_NEIGHBORS,
                              ORCA_TIME_HORIZON_S, ORCA_TIME_HORIZON_OBST_S,
                              float(self._radii[i]) + ORCA_SAFETY_M, float(self._speed[i]),
                              (0.0, 0.0))
            for row in others:
                sim.add_agent(tuple(row[:2]), ORCA_NEIGHBOR_DIST_M, ORCA_MAX_NEIGHBORS,
                              ORCA_TIME_HORIZON_S, ORCA_TIME_HORIZON_OBST_S,
                              float(row[4]) + ORCA_SAFETY_M + ORCA_EXTERNAL_MARGIN_M,
                              EXTERNAL_MAX_SPEED_M_S,
                              tuple(row[2:4]))
            for poly in self._polys:
                sim.add_obstacle([tuple(p) for p in poly.tolist()])
            sim.process_obstacles()
            self._rvo = sim
        sim = self._rvo
        sim.set_time_step(dt)
        for k, i in enumerate(own):
            sim.set_agent_position(k, tuple(self._pos[i]))
            sim.set_agent_velocity(k, tuple(self._vel[i]))
            sim.set_agent_pref_velocity(k, tuple(pref[i]))
        for k, row in enumerate(others, start=len(own)):
            sim.set_agent_position(k, tuple(row[:2]))
            sim.set_agent_velocity(k, tuple(row[2:4]))
            sim.set_agent_pref_velocity(k, tuple(row[2:4]))
        sim.do_step()
        pos = np.array([sim.get_agent_position(k).to_tuple() for k in range(len(own))], float)
        vel = np.array([sim.get_agent_velocity(k).to_tuple() for k in range(len(own))], float)
        return pos, vel

    def _others_rows(self, idx: np.ndarray) -> np.ndarray:
        """(k, 5) the people ``idx`` as given-velocity agents of the other model."""
        return np.column_stack([self._pos[idx], self._vel[idx], self._radii[idx]]).reshape(-1, 5)

    def _step_sf(self, dt: float, ext: np.ndarray, pref: np.ndarray):
        """The social-force group's new positions and velocities (pysocialforce one step)."""
        own = self._sf
        others = np.concatenate([ext, self._others_rows(self._orca)])
        n_own = len(own)
        # goal: a carrot SF_CARROT_M ahead toward the waypoint (the library stops 0.5 m short)
        carrot = self._pos[own] + pref[own] / np.maximum(self._speed[own], 1e-12)[:, None] \
            * SF_CARROT_M
        arrived = self._arrived[own]
        carrot[arrived] = self._pos[own][arrived]
        goals = np.concatenate([carrot, others[:, :2] + others[:, 2:4]])
        state = np.column_stack([np.concatenate([self._pos[own], others[:, :2]]),
                                 np.concatenate([self._vel[own], others[:, 2:4]]), goals])
        if self._sim is None:
            sim = _pysocialforce().Simulator(state.copy(), obstacles=None)
            # walls: points every SF_WALL_STEP_M, ends included (the library's own sampling
            # gives an edge shorter than 0.1 m no point at all and then fails)
            sim.env._obstacles = [_sample_edge(a, b) for poly in self._polys
                                  for a, b in zip(poly, np.roll(poly, -1, axis=0), strict=True)]
            # the library drives a pedestrian at multiplier x its "initial speed": make that
            # product the person's preferred speed (others' rows are overwritten every step)
            initial = np.concatenate([self._speed[own], np.zeros(len(others))]) \
                / SF_SPEED_MULTIPLIER
            sim.peds.initial_speeds = initial
            sim.peds.max_speed_multiplier = SF_SPEED_MULTIPLIER
            sim.peds.max_speeds = initial * SF_SPEED_MULTIPLIER
            sim.peds.agent_radius = float(self._radii[own].max())
            self._sim = sim
        sim = self._sim
        sim.peds.step_width = dt
        sim.peds.state[:, :6] = state
        with np.errstate(invalid="ignore", divide="ignore"):   # 0/0 speeds: its own guard
            sim.step_once()
        del sim.peds.ped_states[:-1], sim.peds.group_states[:-1]  # the library keeps history
        out = sim.peds.state
        return out[:n_own, 0:2].copy(), out[:n_own, 2:4].copy()


def _sample_edge(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(k, 2) points [m] from a to b, at most SF_WALL_STEP_M apart."""
    k = max(2, math.ceil(math.hypot(*(b - a)) / SF_WALL_STEP_M) + 1)
    return np.column_stack([np.linspace(a[0], b[0], k), np.linspace(a[1], b[1], k)])


def load_pysocialforce():
    """pysocialforce, imported once without its side effects (:func:`_pysocialforce`), its
    numba kernels cached on disk (:func:`_cache_kernels`)."""
    return _pysocialforce()


def _cache_kernels(module) -> int:
    """Turn on numba's on-disk cache for ``module``'s compiled kernels; the count turned on.

    pysocialforce compiles its kernels (``@njit`` in ``utils/stateutils.py``) without
    ``cache=True``: every process that ran the model (a crowd world's simulator, a
    social-force planner) compiled them from source again, about 5 s of CPU. Cached as our
    own kernels are, a later process loads the same machine code in about 1 s, numba's
    import included (tests/unit/test_crowd_kernels_cached.py). Only dispatchers that have
    compiled nothing yet are touched; where numba finds no writable cache directory a
    kernel stays uncached and compiles in each process, as before."""
    on = 0
    for obj in vars(module).values():
        if callable(getattr(obj, "enable_caching", None)) and not getattr(obj, "signatures", True):
            try:
                obj.enable_caching()
            except RuntimeError:     # numba: "cannot cache function …: no locator available"
                continue
            on += 1
    return on


def _pysocialforce():
    """Import pysocialforce without its side effects: at import it sets the root logger to
    DEBUG, adds a console handler and opens ``file.log`` in the working directory."""
    if "pysocialforce" in sys.modules:
        return sys.modules["pysocialforce"]
    loggers = {logging.getLogger(), logging.getLogger("root")}
    saved = {lg: (lg.level, list(lg.handlers)) for lg in loggers}
    file_handler, disabled = logging.FileHandler, logging.root.manager.disable
    logging.FileHandler = lambda *a, **k: logging.NullHandler()
    logging.disable(logging.CRITICAL)          # nothing logged while it imports
    try:
        import pysocialforce
    finally:
        logging.FileHandler = file_handler
        logging.disable(disabled)
        for lg, (level, handlers) in saved.items():
            for h in [h for h in lg.handlers if h not in handlers]:
                lg.removeHandler(h)
            lg.setLevel(level)
    from pysocialforce.utils import stateutils
    _cache_kernels(stateutils)
    return pysocialforce
