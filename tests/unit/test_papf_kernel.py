"""The compiled PAPF cycle (nodes/planner/papf/compiled.py) against the numpy steps, bit for bit."""

import dataclasses
import math

import numpy as np
import pytest

from nodes.planner.field import APFParams
from nodes.planner.papf.kernels import HAVE_NUMBA
from nodes.planner.papf.strategy import PAPFParams, PAPFStrategy
from nodes.planner.registry import make_planner
from schemas.messages import Goal, Odometry
from tests.support.toysim import box_segments, cast_scan, simulate, toy_world

pytestmark = pytest.mark.skipif(not HAVE_NUMBA, reason="numba not installed")

APF = APFParams()
VARIANTS = {  # name -> PAPFParams overrides (both paths are run with each)
    "default": {},
    "literal pull, M = 3": {"pull_range_fraction": 0.0, "max_quarks": 3},
    "no ties, quarks within d_q": {"tie_tol_m": 0.0, "motion_quarks_within_d_o": False, "d_q": 0.5},
    "unresolved: eq. 8 on the last path": {"unresolved_global_goal": False, "max_quarks": 2},
    "point quarks (no ball)": {"quark_ball_m": 0.0},
    "M = 0": {"max_quarks": 0},
}


def _scenes(rng, n):
    """Rings with a gap (every prediction stagnates), walls, scattered points; old quarks."""
    out = []
    for k in range(n):
        ang = np.linspace(rng.uniform(0, 0.3), 2 * math.pi - rng.uniform(0, 0.3), 300)
        ring = rng.uniform(0.5, 1.0) * np.column_stack([np.cos(ang), np.sin(ang)])
        wall = np.column_stack([np.full(120, rng.uniform(0.4, 1.2)), np.linspace(-1, 1, 120)])
        scatter = rng.uniform(-1.5, 1.5, (int(rng.integers(0, 300)), 2))
        pts = (ring, wall, scatter, np.zeros((0, 2)))[k % 4]
        quarks = rng.uniform(-0.6, 0.6, (int(rng.integers(0, 14)), 2)) if k % 3 else None
        pos = rng.uniform(-0.05, 0.05, 2)
        goal = pos + rng.uniform(0.5, 4.0) * np.array([math.cos(a := rng.uniform(-1, 1)), math.sin(a)])
        out.append((pos, goal, pts, quarks))
    return out


@pytest.mark.parametrize("variant", sorted(VARIANTS))
def test_compiled_plan_matches_the_numpy_steps_bit_for_bit(variant):
    rng = np.random.default_rng(sorted(VARIANTS).index(variant) + 5)
    seen_quarks = seen_unresolved = 0
    for pos, goal, pts, quarks in _scenes(rng, 40):
        view = _View(pts)
        plans = []
        for numba_on in (True, False):
            s = PAPFStrategy(PAPFParams(**VARIANTS[variant], use_numba=numba_on))
            s.quarks = quarks
            plans.append((s.plan(pos, 0.0, goal, view, APF), s.quarks))
        (a, qa), (b, qb) = plans
        assert a.mode == b.mode and a.searching == b.searching
        assert np.array_equal(a.force, b.force), (a.force, b.force)
        assert a.temporary_goal == b.temporary_goal
        assert np.array_equal(a.predicted_path, b.predicted_path)
        assert np.array_equal(a.debug["top_quarks"], b.debug["top_quarks"]) and np.array_equal(qa, qb)
        assert len(a.debug["abandoned_paths"]) == len(b.debug["abandoned_paths"])
        assert all(np.array_equal(x, y) for x, y in zip(a.debug["abandoned_paths"], b.debug["abandoned_paths"], strict=True))
        seen_quarks += len(a.debug["top_quarks"]) > 0
        seen_unresolved += a.mode == "unresolved"
    if VARIANTS[variant].get("max_quarks", 10) > 0:   # the quark term and eq. 8 with quarks ran
        assert seen_quarks > 5
    if 0 < VARIANTS[variant].get("max_quarks", 10) <= 3:
        assert seen_unresolved > 0


@dataclasses.dataclass
class _View:
    points: np.ndarray


def test_planner_states_identical_with_and_without_numba_in_a_trap():
    """Whole cycles in the bench's worst case (a ring with one narrow gap, M = 10 quarks each cycle)."""
    ring = toy_world(segments=tuple(
        (0.8 * math.cos(a0), 0.8 * math.sin(a0), 0.8 * math.cos(a1), 0.8 * math.sin(a1))
        for a0, a1 in zip(np.linspace(0.05, 2 * math.pi - 0.05, 41)[:-1],
                          np.linspace(0.05, 2 * math.pi - 0.05, 41)[1:], strict=True)))
    out = []
    for sets in (["persist_quarks=false"], ["persist_quarks=false", "use_numba=false"]):
        pl = make_planner("papf", sets=sets)
        pl.set_goal(Goal(stamp_ns=0, x=3.0, y=0.0))
        states = []
        for k, x in enumerate(np.linspace(-0.05, 0.05, 15)):
            pl.state = "driving"
            cmd, state, _status = pl.step(cast_scan(ring, x, 0.0, 0.0, stamp_ns=k + 1),
                                          Odometry(stamp_ns=k + 1, x=x, y=0.0, yaw=0.0, v=0.0, w=0.0))
            states.append((cmd.to_bytes(), dataclasses.replace(state, compute_ns=0).to_bytes()))
        out.append(states)
    assert out[0] == out[1]


def test_run_without_ties_identical_with_and_without_numba():
    """A run round a box with eq. 8's ties off (the paper's rule: the strict maximum, where
    rounding noise decides among points on a straight path) and quarks within d_q."""
    world = toy_world(segments=box_segments(2.0, 0.0, 0.4, 0.4))
    sets = ["tie_tol_m=0", "motion_quarks_within_d_o=false", "d_q=0.5"]
    runs = [simulate(make_planner("papf", sets=sets + extra), world, goal=(5.0, 0.0),
                     max_time_s=30, keep_states=True) for extra in ([], ["use_numba=false"])]
    fast, slow = ([dataclasses.replace(s, compute_ns=0).to_bytes() for s in r.states] for r in runs)
    assert fast == slow and np.array_equal(runs[0].path, runs[1].path)


def test_debug_state_is_in_the_messages_own_form():
    """Planner._state builds PlannerState without normalising: the values must be exactly
    what the constructor would make (tuples of Python floats)."""
    world = toy_world(segments=box_segments(1.2, 0.0, 0.4, 0.4))
    for name in ("papf", "apf", "arapf", "wang"):
        pl = make_planner(name)
        pl.set_goal(Goal(stamp_ns=0, x=4.0, y=0.0))
        _cmd, state, _status = pl.step(cast_scan(world, 0.0, 0.0, 0.0, stamp_ns=1),
                                       Odometry(stamp_ns=1, x=0.0, y=0.0, yaw=0.0, v=0.0, w=0.0))
        values = {f: getattr(state, f) for f, _k, _m in state._FIELDS}
        again = type(state)(**values)
        assert again == state and again.to_bytes() == state.to_bytes()
        for f, kind, _m in state._FIELDS:
            assert type(values[f]) is type(getattr(again, f)), f
            if kind in ("points", "paths"):
                flat = values[f] if kind == "points" else [p for path in values[f] for p in path]
                assert all(type(p) is tuple and type(p[0]) is float for p in flat), f


def test_scan_points_numba_and_numpy_identical():
    """Beams -> points with nan, +-inf and out-of-range returns, finite and infinite limits."""
    from nodes.planner.scan_kernel import scan_points

    rng = np.random.default_rng(4)
    for k in range(40):
        ranges = rng.uniform(-1.0, 14.0, 300)
        ranges[rng.random(300) < 0.1] = np.nan
        ranges[rng.random(300) < 0.1] = np.inf
        ranges[rng.random(300) < 0.05] = -np.inf
        angles = rng.uniform(-7, 7) + 0.021 * np.arange(300)
        limits = (0.2, 12.0) if k % 3 else (0.2, np.inf)
        args = (ranges, np.cos(angles), np.sin(angles), *limits, rng.uniform(-5, 5, 2))
        fast, slow = scan_points(*args, use_numba=True), scan_points(*args, use_numba=False)
        for a, b in zip(fast, slow, strict=True):
            assert a.dtype == b.dtype and np.array_equal(a, b)
        assert fast[2].sum() > 100 and not np.isfinite(fast[0][~fast[2]]).any()


def test_kernel_params_built_once_per_settings_from_the_papers_products():
    """One KernelParams per (APFParams, PAPFParams) pair: the same object again while the
    settings stay, a new one when they change; its gains are eq. 2's and eq. 7's products."""
    from nodes.planner.papf.params import kernel_params

    apf, pp = APFParams(), PAPFParams()
    kp = kernel_params(apf, pp)
    assert kernel_params(apf, pp) is kp
    assert kp.g_goal == apf.k_vg * apf.q_v * apf.q_g and kp.g_obs == apf.k_vo * apf.q_v * apf.q_o
    assert kp.g_q == pp.k_vq_factor * apf.k_vo * apf.q_v * pp.q_q
    assert (kp.i_max, kp.n_stag, kp.q_lim) == (pp.i_max, pp.n_stag, apf.d_o)
    other = kernel_params(apf, PAPFParams(motion_quarks_within_d_o=False, d_q=1.5))
    assert other is not kp and other.q_lim == 1.5
