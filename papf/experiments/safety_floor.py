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
}
WORLDS = ("energy-blocking", "papf-test-1")
TIMEOUT_S = 200.0   # [s] sim time: energy-blocking takes ~100 s at the defaults

# The car planner's obstacle field (IAPF eq. 11: gain * exp(a_x dx^2 + a_y dy^2)), swept on the
# paper's four car-scale cases (``--car``). a_x, a_y < 0: towards 0 the field stops decaying
# and its gradient (the avoiding force) vanishes, so their floor bounds them away from 0.
CAR_SWEEP: dict[str, tuple[tuple[str, ...], tuple[float, ...]]] = {
    "obstacle_gain": ((CAR,), (100.0, 30.0, 10.0, 3.0, 1.0, 0.3, 0.1, 0.01)),
    "a_x": ((CAR,), (-0.01, -0.003, -0.001, -0.0003, -0.0001, -1e-05)),
    "a_y": ((CAR,), (-0.2, -0.1, -0.05, -0.02, -0.01, -0.001)),
}
CAR_WORLDS = ("iapf-case-a", "iapf-case-b", "iapf-case-c", "iapf-case-d")


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


def cases(worlds=WORLDS, combos: bool = False, sweep=None) -> Iterator[Case]:
    """Every (world, planner, parameter, value) of ``sweep`` (default :data:`SWEEP`); with
    ``combos``, the runs of :data:`COMBOS` instead (the strength floor reached by several
    factors at once)."""
    for world in worlds:
        if combos:
            for planner, sets in COMBOS:
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
    """One offline run of ``case``; its CSV row."""
    from papf.offline.run import simulate

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
    for param, (_, values) in (sweep or SWEEP).items():
        safe = None
        for v in values:
            hit = [r for r in rows if r["param"] == param and r["value"] == f"{v:g}"]
            if not hit or any(r["outcome"] == "collision" for r in hit):
                break
            safe = v
        if safe is not None:
            out[param] = safe
    return out


def run(out: Path, worlds=WORLDS, progress=print, car: bool = False) -> dict[str, float]:
    """Sweep into ``out`` (appending; runs already there skipped), then :data:`COMBOS`;
    returns the single-factor floors. ``car``: :data:`CAR_SWEEP` on :data:`CAR_WORLDS` instead.

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
    sweep = CAR_SWEEP if car else SWEEP
    for combos in ((False,) if car else (False, True)):
        for case in cases(CAR_WORLDS if car else worlds, combos, sweep):
            if case.key in have:
                continue
            row = run_case(case)
            write_rows(out, FIELDS, [row], append=True)   # each run on disk as it ends
            rows.append(row)
            progress(f"{case.world} {case.planner} {' '.join(case.sets)}: {row['outcome']} "
                     f"(min clearance {row['min_clearance_m']} m)")
    return floors_of(rows, sweep)


def _read(path: Path) -> list[dict]:
    if not path.exists():
        return []
    with path.open(newline="") as fh:
        return list(csv.DictReader(fh))
