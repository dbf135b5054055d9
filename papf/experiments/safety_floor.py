"""The safety parameters' floors, measured: each swept downwards alone, offline, on worlds with
obstacles in the path (``papf experiment safety-floor``).

The floor is the smallest swept value at which no planner collided on any world;
:mod:`nodes.planner.settings` takes its lower bounds from the table this writes
(``docs/data/safety-floor.csv``, docs/planners.md "Safety floors"). Details: :func:`run`.
"""

from __future__ import annotations

import csv
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from nodes.planner.registry import one_with_role

# the planners each field acts in, by their roles (nodes/planner/registry.py)
APF_PAIR = (one_with_role("papf-baseline"), one_with_role("papf-proposed"))
ARAPF = one_with_role("arapf-proposed")
WANG = one_with_role("wang-proposed")
CAR = one_with_role("car-proposed")

FIELDS = ("world", "planner", "param", "value", "outcome", "collisions", "min_clearance_m",
          "duration_s", "path_length_m")

# Each safety parameter: the planners it acts in, and the values swept (downwards from the default).
SWEEP: dict[str, tuple[tuple[str, ...], tuple[float, ...]]] = {
    "d_o": (APF_PAIR, (0.5, 0.3, 0.25, 0.2, 0.15, 0.1, 0.05, 0.01)),
    "k_vo_l": (APF_PAIR, (10.0, 2.0, 1.0, 0.5, 0.1, 0.01)),
    "q_o": (APF_PAIR, (-1.0, -0.5, -0.2, -0.1, -0.01, -0.001)),
    "k_ro_l": ((ARAPF,), (5.0, 1.0, 0.5, 0.1, 0.01)),
    "k_rep_l": ((WANG,), (5.0, 1.0, 0.5, 0.1, 0.01)),
    "rho_0": ((WANG,), (0.5, 0.3, 0.2, 0.1, 0.05, 0.01)),
    # the turn-rate limit at the bottom of its range: a robot that cannot turn away
    "w_max": (APF_PAIR, (1.0, 0.5, 0.2, 0.1, 0.01)),
}
WORLDS = ("energy-blocking", "papf-test-1")
TIMEOUT_S = 200.0   # [s] sim time: energy-blocking takes ~100 s at the defaults

# The car planner's obstacle field (IAPF eq. 11: gain * exp(a_x dx^2 + a_y dy^2)), swept on the
# paper's four car-scale cases (``--car``). a_x, a_y < 0: towards 0 the field stops decaying
# and its gradient (the avoiding force) vanishes, so their floor bounds them away from 0.
CAR_SWEEP: dict[str, tuple[tuple[str, ...], tuple[float, ...]]] = {
    "obstacle_gain": ((CAR,), (100.0, 30.0, 10.0, 3.0, 1.0, 0.3, 0.1, 0.01,
                               300.0, 1e3, 1e4, 1e5)),   # the strong side (caps), issue 31
    "a_x": ((CAR,), (-0.01, -0.003, -0.001, -0.0003, -0.0001, -1e-05,
                     -0.03, -0.1, -0.3, -1.0, -3.0)),     # ... a field narrowed to nothing
    "a_y": ((CAR,), (-0.2, -0.1, -0.05, -0.02, -0.01, -0.001,
                     -0.5, -1.0, -3.0, -10.0, -30.0)),
}
CAR_WORLDS = ("iapf-case-a", "iapf-case-b", "iapf-case-c", "iapf-case-d")

# The other side of the balance (``--attraction``): a goal pull strong enough outweighs every
# obstacle's push, and the robot drives into what lies on the line. Each attraction gain (and
# each setting that pushes the robot on) swept upwards alone, the others at their defaults, on
# :data:`WORLDS`; the "floor" :func:`floors_of` finds is then a ceiling (the largest swept
# value at which nothing collided).
WANG_APF = one_with_role("wang-baseline")
ATTRACTION_SWEEP: dict[str, tuple[tuple[str, ...], tuple[float, ...]]] = {
    "k_vg": ((*APF_PAIR, ARAPF), (5.0, 10.0, 25.0, 50.0, 75.0, 100.0, 250.0, 1000.0)),
    "q_g": (APF_PAIR, (1.0, 2.0, 5.0, 10.0, 50.0)),
    "k_att": ((WANG, WANG_APF), (10.0, 20.0, 30.0, 40.0, 50.0, 100.0, 250.0, 1000.0)),
    # the other settings that push on, at the top of their ranges: the speed limit, the
    # heading error the robot still drives at (eq. 5), and Wang's control point ahead
    "v_max": ((*APF_PAIR, ARAPF), (0.1, 0.2, 0.3, 0.5, 0.9)),
    "theta_err_max_deg": (APF_PAIR, (30.0, 60.0, 90.0, 180.0)),
    "control_offset_m": ((WANG,), (0.05, 0.1, 0.25, 0.3, 0.4, 0.5, 1.0)),
}
# Is the tolerated ratio a property of the balance, not of one gain? The APF pair at the
# repulsion's floor (k_vo_l q_v q_o = 2, nodes/planner/settings.py), Wang's at twice its default
# repulsion, each at ratios 0.5 .. 10.
ATTRACTION_COMBOS: tuple[tuple[str, tuple[str, ...]], ...] = tuple(
    (planner, ("k_vo_l=2.0", f"k_vg={k!r}")) for planner in APF_PAIR for k in (1.0, 2.0, 5.0, 10.0)
) + tuple((WANG, ("k_rep_l=10.0", f"k_att={k!r}")) for k in (20.0, 40.0, 50.0, 100.0))
ATTRACTION_FIELDS = (*FIELDS, "ratio")
ATTRACTION_GAINS = ("k_vg", "q_g", "k_att", "combo")   # the rows that vary the ratio


def _unchecked(planner: str, sets):
    """(APFParams, the planner's Params) of ``sets`` (``name=value`` numbers), not checked."""
    import dataclasses

    from nodes.planner.field import APFParams
    from nodes.planner.registry import PLANNERS

    apf, algo = APFParams(), PLANNERS[planner].Params()
    shared = {f.name for f in dataclasses.fields(APFParams)}
    for text in sets:
        name, value = text.split("=", 1)
        if name in shared:
            apf = dataclasses.replace(apf, **{name: float(value)})
        else:
            algo = dataclasses.replace(algo, **{name: float(value)})
    return apf, algo


def planner_beyond_ranges(planner: str, sets):
    """A :class:`~nodes.planner.core.Planner` with ``sets`` applied as given: for measuring
    past the ranges' ends only (never reachable from a command line, a file or the bus)."""
    from nodes.planner.core import Planner
    from nodes.planner.registry import PLANNERS

    apf, algo = _unchecked(planner, sets)
    return Planner(PLANNERS[planner](algo), apf)


def attraction_ratio(planner: str, sets) -> float:
    """The attraction-to-repulsion ratio of ``planner`` with ``sets`` (``name=value`` strings,
    the rest at defaults): eq. 2's ``k_VG q_G / (k_VO L |q_O|)`` for the APF family (``q_V`` is
    in both), ``k_att / k_rep_l`` for Wang's (nodes/planner/settings.py ``attraction_ratio``)."""
    from nodes.planner.settings import attraction_ratio as ratio

    return ratio(*_unchecked(planner, sets))   # beyond the ranges on purpose, as the runs


@dataclass(frozen=True)
class Case:
    world: str
    planner: str
    param: str            # "floors": every parameter of FLOORS at once
    value: float
    sets: tuple[str, ...]

    @property
    def key(self) -> tuple[str, str, str, str]:
        """The case's identity: (world, planner, parameter, value label)."""
        return (self.world, self.planner, self.param, self.label)

    @property
    def label(self) -> str:
        """The value as shown: the number, or the combination's settings."""
        return " ".join(self.sets) if self.param == "combo" else f"{self.value:g}"


def cases(worlds=WORLDS, combos: bool = False, sweep=None, combo_runs=None) -> Iterator[Case]:
    """Every (world, planner, parameter, value) of ``sweep`` (default :data:`SWEEP`); with
    ``combos``, the runs of ``combo_runs`` (default :data:`COMBOS`: the strength floor reached
    by several factors at once) instead."""
    for world in worlds:
        if combos:
            for planner, sets in (COMBOS if combo_runs is None else combo_runs):
                yield Case(world, planner, "combo", 0.0, sets)
            continue
        for param, (planners, values) in (sweep or SWEEP).items():
            for planner in planners:
                for v in values:
                    yield Case(world, planner, param, v, (f"{param}={v!r}",))


# Eq. 2's obstacle force is k q_V q_O / d^2: the floors of the single factors do not compose
# (each at its floor is 250 times weaker than the default). The product has its own floor
# (nodes/planner/settings.py REPULSION_MIN): these runs reach it with d_o at its floor.
COMBOS: tuple[tuple[str, tuple[str, ...]], ...] = tuple(
    (planner, ("d_o=0.25", *sets)) for planner in APF_PAIR for sets in (
        ("k_vo_l=2.0", "q_v=-1.0", "q_o=-1.0"), ("k_vo_l=10.0", "q_v=-1.0", "q_o=-0.2"),
        ("k_vo_l=10.0", "q_v=-0.2", "q_o=-1.0"), ("k_vo_l=50.0", "q_v=-0.2", "q_o=-0.2"))
) + ((ARAPF, ("k_ro_l=0.5", "q_v=-1.0", "q_o=-1.0")),
     (ARAPF, ("k_vo_l=50.0", "k_ro_l=12.5", "q_v=-0.2", "q_o=-0.2")))


def done_keys(path: Path) -> set[tuple[str, str, str, str]]:
    """The runs already in the CSV at ``path`` (none when it does not exist)."""
    if not path.exists():
        return set()
    with path.open(newline="") as fh:
        return {(r["world"], r["planner"], r["param"], r["value"]) for r in csv.DictReader(fh)}


def run_case(case: Case, seed: int = 0) -> dict:
    """One offline run of ``case``; its CSV row.

    On the ROSbot worlds the planner is built from the settings without the range checks
    (:func:`planner_beyond_ranges`): the sweep measures what happens past the ends of the
    ranges, which the checks exist to refuse — so the table can be made again from nothing.
    The run is otherwise :func:`papf.offline.run.simulate`'s (the same loop, LiDAR, gate)."""
    from papf.offline.plan import _plan_2d
    from papf.offline.run import simulate
    from worlds import load_world

    world = load_world(case.world)
    if world.vehicle == "rosbot" and world.dims == 2 and not (world.robots or world.has_people):
        s = _plan_2d(world, planner_beyond_ranges(case.planner, case.sets), case.planner, seed,
                     TIMEOUT_S, 0.1, None, False).summary()
    else:
        s = simulate(case.world, case.planner, params=list(case.sets), seed=seed,
                     max_time_s=TIMEOUT_S).summary()
    return {"world": case.world, "planner": case.planner, "param": case.param,
            "value": case.label, "outcome": s["outcome"], "collisions": s["collisions"],
            "min_clearance_m": round(s["min_clearance_m"], 3), "duration_s": round(s["duration_s"], 1),
            "path_length_m": round(s["path_length_m"], 2)}


def floors_of(rows: list[dict], sweep=None) -> dict[str, float]:
    """Per parameter, the smallest-magnitude swept value down to which no run collided
    (the sweep stops counting at the first value that collided on any world or planner)."""
    out = {}
    for param, (planners, values) in (sweep or SWEEP).items():
        safe = None
        for v in values:
            hit = [r for r in rows if r["param"] == param and r["value"] == f"{v:g}"
                   and r["planner"] in planners]
            if not hit or any(r["outcome"] == "collision" for r in hit):
                break
            safe = v
        if safe is not None:
            out[param] = safe
    return out


def ratio_limit(rows: list[dict], planners) -> float | None:
    """The largest attraction-to-repulsion ratio of ``planners``' rows below the smallest that
    collided (None: none of them ran without a collision below it)."""
    mine = [(float(r["ratio"]), r["outcome"]) for r in rows
            if r["planner"] in planners and r["param"] in ATTRACTION_GAINS]
    worst = min((x for x, o in mine if o == "collision"), default=float("inf"))
    safe = [x for x, o in mine if o != "collision" and x < worst]
    return max(safe, default=None)


def run(out: Path, worlds=WORLDS, progress=print, car: bool = False,
        attraction: bool = False) -> dict[str, float]:
    """Sweep into ``out`` (appending; runs already there skipped), then :data:`COMBOS`;
    returns the single-factor floors. ``car``: :data:`CAR_SWEEP` on :data:`CAR_WORLDS` instead.
    ``attraction``: :data:`ATTRACTION_SWEEP` and :data:`ATTRACTION_COMBOS` (each row with its
    ``ratio``), returning the gains' ceilings and each family's tolerated ratio.

    A safety parameter's range must exclude every value that switches its protection off, and a
    value only just above zero does that as surely as zero (``d_o = 1e-9`` m repels from nothing).
    The floor is therefore the smallest swept value at which every planner on every world still
    avoided every obstacle (no collision); :mod:`nodes.planner.settings` takes its lower bounds
    from the table this writes (``docs/data/safety-floor.csv``, docs/planners.md "Safety floors").
    The last rows per world (:data:`COMBOS`) reach the floor of eq. 2's product ``k q_V q_O``
    (what repels) through several factors at once. Each finished run is appended to the CSV as it ends, and a
    run already in the CSV is not run again (``--resume``).
    """
    from bench.csvrows import write_rows

    rows = _read(out)
    have = done_keys(out)
    sweep = CAR_SWEEP if car else ATTRACTION_SWEEP if attraction else SWEEP
    fields = ATTRACTION_FIELDS if attraction else FIELDS
    for combos in ((False,) if car else (False, True)):
        for case in cases(CAR_WORLDS if car else worlds, combos, sweep,
                          ATTRACTION_COMBOS if attraction else None):
            if case.key in have:
                continue
            row = run_case(case)
            if attraction:
                row["ratio"] = round(attraction_ratio(case.planner, case.sets), 4)
            write_rows(out, fields, [row], append=True)   # each run on disk as it ends
            rows.append(row)
            progress(f"{case.world} {case.planner} {' '.join(case.sets)}: {row['outcome']} "
                     f"(min clearance {row['min_clearance_m']} m)")
    found = floors_of(rows, sweep)
    if attraction:
        for family, planners in (("ratio_apf", (*APF_PAIR, ARAPF)), ("ratio_wang", (WANG,))):
            limit = ratio_limit(rows, planners)
            if limit is not None:
                found[family] = limit
    return found


def _read(path: Path) -> list[dict]:
    if not path.exists():
        return []
    with path.open(newline="") as fh:
        return list(csv.DictReader(fh))
