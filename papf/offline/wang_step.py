"""Wang's MATLAB simulation as published: a point stepping a fixed length along the force.

Wang (papers/improved-apf-wang.txt, Sec. 4, Table 1) moves a point from the start by a
constant step ``I = 0.5`` along the resultant force, for at most ``J = 200`` iterations of
the force function, on a map with round obstacles whose centres and radii are known (no
sensor). :func:`fixed_step` does that, on a packaged world (cylinders in 2-D, spheres in
3-D), in the paper's map units (``units_per_m``: 1 for the Table 1 maps, which are
written in map units; 10 for the 3-D worlds, which are stored scaled 0.1 to metres).

Two fields:

- ``traditional`` — eqs. 1-5 as :func:`nodes.planner.wang.strategy.traditional_force` reads them (the
  ROSbot planner ``wang-apf``'s field, one "point" per obstacle centre). Table 1: K_att = 10,
  K_rep = 2, rho_0 = 20.
- ``improved`` — eqs. 6-8 as :func:`nodes.planner.wang.strategy.wang_force` reads them (the ROSbot
  planner's field), on the obstacle centres with R_0 = the obstacle's radius in eq. 6, and
  K_rep = 5 (Sec. 4: "the basic parameters remained unchanged ... except for the repulsion
  gain coefficient").

Outcomes: ``reached`` (the point comes within ``step / 2`` of the target: the closest a
fixed-step walk straight at it is sure to get), ``collision`` (a step ends inside an
obstacle or its segment crosses one), ``failed`` (``J`` iterations spent: the paper's
"local oscillations", "failed to reach the final target point").

:func:`fixed_step` returns the one offline :class:`~papf.offline.result.PlanResult`, in metres
(``units_per_m`` says the map scale; ``cycles`` the iterations made).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from common.errors import ConfigError
from nodes.planner.registry import one_with_role
from nodes.planner.wang.strategy import WangAPFParams, WangParams, traditional_force, wang_force
from papf.offline.result import PlanResult
from worlds import World, load_world

METHODS = ("traditional", "improved")
PLANNER_METHODS = {one_with_role("wang-baseline"): "traditional",   # the registry's planners
                   one_with_role("wang-proposed"): "improved"}
CLEARANCE_CAP_M = 1.0   # [m] clearances above this are reported as the cap (as the other motions)


@dataclass(frozen=True)
class PointParams:
    """Wang Table 1 (map units)."""

    step: float = 0.5          # I, step size
    iterations: int = 200      # J, iterations of the force function
    k_att: float = 10.0        # K_att
    k_rep: float = 2.0         # K_rep (traditional; the improved run uses k_rep_improved)
    k_rep_improved: float = 5.0  # Sec. 4: K_rep = 5 for the improved APF
    rho_0: float = 20.0        # influence radius of the obstacles


def obstacles_of(world: World, units_per_m: float) -> tuple[np.ndarray, np.ndarray]:
    """(centres (K, D), radii (K,)) of the world's round obstacles, in map units."""
    dims = world.dims
    cs, rs = [], []
    for i, ob in enumerate(world.obstacles):
        if not ob.model.round:
            raise ConfigError(f"world {world.name!r}: obstacles[{i}] is a {ob.kind}; Wang's point "
                              "simulation takes round obstacles only (cylinders, spheres)")
        cs.append(ob.center[:dims])
        rs.append(ob.radius)
    return (np.array(cs, float).reshape(-1, dims) * units_per_m, np.array(rs, float) * units_per_m)


def _traditional(pp: PointParams) -> WangAPFParams:
    """Table 1's field as the planner's parameters: one "point" (L = 1) per obstacle centre."""
    return WangAPFParams(k_att=pp.k_att, k_rep_l=pp.k_rep, lidar_points=1, rho_0=pp.rho_0)


def _improved(pp: PointParams, r_0: float) -> WangParams:
    return WangParams(k_att=pp.k_att, k_rep_l=pp.k_rep_improved, lidar_points=1, rho_0=pp.rho_0,
                      r_0=r_0, control_offset_m=0.0)


def _clearance(p, q, centres, radii) -> float:
    """Smallest distance from the segment p-q to an obstacle surface (< 0: it enters one)."""
    if not len(centres):
        return math.inf
    d = q - p
    L2 = float(d @ d)
    t = np.clip(((centres - p) @ d) / L2, 0.0, 1.0) if L2 > 0 else np.zeros(len(centres))
    closest = p + t[:, None] * d
    return float(np.min(np.linalg.norm(centres - closest, axis=1) - radii))


def fixed_step(world: World | str, method: str, pp: PointParams | None = None,
               units_per_m: float | None = None) -> PlanResult:
    """Wang's point walk on ``world`` with the ``traditional`` or ``improved`` field (the
    planners ``wang-apf`` and ``wang``), in the paper's map units; the result in metres."""
    if method not in METHODS:
        raise ConfigError(f"method {method!r}; valid: {list(METHODS)}")
    world = world if isinstance(world, World) else load_world(world)
    pp = pp or PointParams()
    scale = units_per_m if units_per_m is not None else (10.0 if world.dims == 3 else 1.0)
    centres, radii = obstacles_of(world, scale)
    goal = np.array(world.goal[: world.dims], float) * scale
    pos = np.array(world.start[: world.dims], float) * scale
    wps = [_improved(pp, float(r)) for r in radii] if method == "improved" else []
    trad = _traditional(pp)
    path, clear, outcome, used = [pos.copy()], math.inf, "failed", 0
    for k in range(1, pp.iterations + 1):
        used = k
        if method == "traditional":
            f = traditional_force(pos, goal, centres, trad)
        else:   # R_0 of eq. 6 is the radius of the nearest obstacle
            near = int(np.argmin(np.linalg.norm(centres - pos, axis=1))) if len(centres) else 0
            f = wang_force(pos, goal, centres, wps[near] if wps else _improved(pp, 0.0))
        n = float(np.linalg.norm(f))
        nxt = pos + (pp.step * f / n if n > 0 else 0.0)
        c = _clearance(pos, nxt, centres, radii)
        clear = min(clear, c)
        pos = nxt
        path.append(pos.copy())
        if c < 0:
            outcome = "collision"
            break
        if np.linalg.norm(goal - pos) <= pp.step / 2:
            outcome = "reached"
            break
    return _result(world, method, outcome, used, np.array(path) / scale, clear / scale, pp, scale)


def _result(world: World, method: str, outcome: str, iterations: int, path: np.ndarray,
            clear_m: float, pp: PointParams, scale: float) -> PlanResult:
    """The walk as the one offline result (no time: ``times`` counts the iterations)."""
    reason = {"reached": f"within {pp.step / 2:g} map units of the target",
              "collision": f"a step enters an obstacle near {np.round(path[-1], 2).tolist()}",
              "failed": f"{iterations} iterations spent (Wang's local oscillations)"}[outcome]
    planner = {m: p for p, m in PLANNER_METHODS.items()}[method]
    return PlanResult(world=world.name, planner=planner, seed=0, outcome=outcome, reason=reason,
                      path=path, times=np.arange(path.shape[0], dtype=float),
                      headings=np.zeros(0), duration_s=0.0, sim_time_s=0.0,
                      min_clearance_m=min(clear_m, CLEARANCE_CAP_M),
                      collisions=int(outcome == "collision"), motion="fixed-step",
                      cycles=iterations, units_per_m=scale)
