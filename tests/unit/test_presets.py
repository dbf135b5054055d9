"""Planner presets (``--preset paper|default``) and PAPF's deviations, each switchable alone (and
``papf experiment deviations``' variants, each switching one setting)."""

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from common.errors import ConfigError
from nodes.planner.core import scan_view
from nodes.planner.field import APFParams
from nodes.planner.papf.strategy import PAPER_PRESET, PAPFParams, PAPFStrategy, predict, quark_force
from nodes.planner.registry import PLANNERS, load_params, preset_sets, preset_settings
from papf.experiments.paper_study import DEVIATIONS, READINGS, _turning, _variants
from papf.experiments.trials import variants
from schemas.messages import Odometry
from tests.support.toysim import cast_scan, toy_world

APF = APFParams()
PAPER = PAPFParams(**PAPER_PRESET)
NO_POINTS = np.zeros((0, 2))


def test_default_preset_changes_nothing_and_paper_switches_every_deviation_off():
    for planner in PLANNERS:
        assert load_params(planner) == load_params(planner, sets=["preset=default"])
    _apf, papf = load_params("papf", sets=["preset=paper"])
    assert papf == PAPER
    assert (papf.pull_range_fraction, papf.quark_ball_m, papf.tie_tol_m) == (0.0, 0.0, 0.0)
    assert not (papf.motion_quarks_within_d_o or papf.unresolved_global_goal or papf.stop_at_goal
                or papf.quark_restarts_watch or papf.replace_oldest_quark)
    # quarks are placed obstacles (kept); d_q, like d_o, has no value in the paper: ours in both,
    # one range for prediction and motion (motion_quarks_within_d_o off)
    assert papf.persist_quarks and papf.d_q == PAPFParams().d_q
    _apf, ar = load_params("arapf", sets=["preset=paper"])
    assert not (ar.range_limited or ar.wall_range_limited or ar.follow)
    assert load_params("wang", sets=["preset=paper"])[1].control_offset_m == 0.0


def test_a_single_deviation_switches_back_whatever_the_order():
    for sets in (["preset=paper", "pull_range_fraction=1"], ["pull_range_fraction=1", "preset=paper"]):
        _apf, p = load_params("papf", sets=sets)
        assert p == dataclasses.replace(PAPER, pull_range_fraction=1.0)


def test_preset_from_a_file(tmp_path):
    f = tmp_path / "p.toml"
    f.write_text('preset = "paper"\n[papf]\nstop_at_goal = true\n')
    assert load_params("papf", f)[1] == dataclasses.replace(PAPER, stop_at_goal=True)


def test_unknown_preset_is_a_config_error():
    with pytest.raises(ConfigError, match="valid: \\['default', 'paper'\\]"):
        load_params("papf", sets=["preset=literal"])
    with pytest.raises(ConfigError):
        preset_sets("fast")
    assert preset_sets("default") == [] and preset_sets("paper") == ["preset=paper"]


def test_variants_run_a_planner_without_a_paper_preset_once():
    assert preset_settings("apf", "paper") == {}
    assert variants(["apf", "papf"], ["default", "paper"]) == [
        ("apf", "default"), ("papf", "default"), ("papf", "paper")]


def test_stop_at_goal_off_predicts_every_step_and_checks_stagnation_at_the_goal():
    goal = np.array([0.5, 0.0])
    on = predict(np.zeros(2), goal, NO_POINTS, APF, PAPFParams())
    off = predict(np.zeros(2), goal, NO_POINTS, APF, dataclasses.replace(PAPFParams(), stop_at_goal=False))
    assert on.reached_goal and on.path.shape[0] == 17
    assert not off.reached_goal and off.path.shape[0] == PAPFParams().i_max + 1
    # the literal prediction oscillates about the goal: a stagnation, quarks on the goal
    assert off.quarks.shape[0] >= 1 and np.linalg.norm(off.quarks[0] - goal) < 0.05


def test_motion_quark_range_and_ball_switch_alone():
    k = PAPFParams().k_vq_factor * APF.k_vo
    at_1m = np.array([[1.0, 0.0]])                  # beyond d_o, within d_q = 2 m
    assert not quark_force(np.zeros(2), at_1m, APF, PAPFParams()).any()
    far = dataclasses.replace(PAPFParams(), motion_quarks_within_d_o=False)
    np.testing.assert_allclose(quark_force(np.zeros(2), at_1m, APF, far), [-k, 0.0], rtol=1e-12)
    near = np.array([[0.1, 0.0]])
    point = dataclasses.replace(PAPFParams(), quark_ball_m=0.0)   # eq. 7: 1 / r^2 all the way in
    np.testing.assert_allclose(quark_force(np.zeros(2), near, APF, point), [-k / 0.01, 0.0], rtol=1e-12)


def _ring_view():
    angles = np.linspace(0.05, 2 * np.pi - 0.05, 300)
    ring = 0.6 * np.column_stack([np.cos(angles), np.sin(angles)])
    view = scan_view(cast_scan(toy_world(circles=()), 0.0, 0.0, 0.0),
                     Odometry(stamp_ns=0, x=0.0, y=0.0, yaw=0.0, v=0.0, w=0.0))
    return type(view)(view.origin, view.angles, view.ranges, ring, view.valid)


def test_fallback_after_m_repetitions_switches_alone():
    goal = np.array([3.0, 0.0])
    ours = PAPFStrategy().plan(np.zeros(2), 0.0, goal, _ring_view(), APF)
    assert ours.mode == "unresolved" and ours.temporary_goal == (3.0, 0.0) and ours.searching
    lit = PAPFStrategy(dataclasses.replace(PAPFParams(), unresolved_global_goal=False,
                                           quark_restarts_watch=False))
    plan = lit.plan(np.zeros(2), 0.0, goal, _ring_view(), APF)
    assert plan.mode == "unresolved" and plan.temporary_goal != (3.0, 0.0)   # eq. 8 on the last path
    assert np.linalg.norm(plan.temporary_goal) < 0.6                          # inside the ring
    assert not plan.searching                    # the watch is not told about the search


def test_quarks_capped_at_m_per_goal_switches_alone():
    goal, ring, m = np.array([3.0, 0.0]), _ring_view().points, PAPFParams().max_quarks
    kept = np.column_stack([np.full(9, -5.0), np.arange(9.0)])   # nine placed earlier, out of range
    ours = predict(np.zeros(2), goal, ring, APF, PAPFParams(), kept)    # the ring traps every path
    assert len(ours.abandoned) == m and ours.quarks.shape[0] == m and not ours.resolved
    assert not np.isin(ours.quarks[:, 0], -5.0).any()               # the oldest gave way
    cap = dataclasses.replace(PAPFParams(), replace_oldest_quark=False)
    capped = predict(np.zeros(2), goal, ring, APF, cap, kept)
    assert len(capped.abandoned) == 1 and capped.quarks.shape[0] == m and not capped.resolved
    np.testing.assert_array_equal(capped.quarks[:9], kept)        # none given up
    full = predict(np.zeros(2), goal, ring, APF, cap, capped.quarks)
    assert not full.abandoned and not full.resolved
    np.testing.assert_array_equal(full.quarks, capped.quarks)
    # with room for all M, the loop (replace_oldest_quark off) gives the kernel's result
    loop, kern = predict(np.zeros(2), goal, ring, APF, cap), predict(np.zeros(2), goal, ring, APF, PAPFParams())
    np.testing.assert_array_equal(loop.path, kern.path)
    np.testing.assert_array_equal(loop.quarks, kern.quarks)


def test_one_energy_model_by_default_everywhere():
    """Every packaged profile, papf run, the experiments and the meter default to one model."""
    from nodes.energy_meter.models import DEFAULT_MODEL
    from papf.cli import build_parser
    from papf.experiments.energy import EnergyExperiment
    from papf.launch.profile import load_profile, packaged_profiles
    from papf.launch.run import RunConfig

    for name in packaged_profiles():
        model = load_profile(name).defaults.get("energy_model")
        assert model in (None, DEFAULT_MODEL), f"profile {name}: energy_model {model}"
    assert build_parser().parse_args(["run", "--world", "open"]).energy_model == DEFAULT_MODEL
    assert build_parser().parse_args(["experiment", "energy"]).energy_model == DEFAULT_MODEL
    assert RunConfig(world="open").energy_model == DEFAULT_MODEL
    assert EnergyExperiment(out=Path(".")).energy_model == DEFAULT_MODEL


def test_deviation_variants_switch_one_setting_each():
    v = dict(_variants(both=True))
    assert len(_variants()) == 2 + len(READINGS) + len(DEVIATIONS)
    assert v["paper"] == ["preset=paper"] and v["default"] == []
    for name, value, _what in READINGS:
        assert v[f"paper with {name}={value}"] == ["preset=paper", f"{name}={value}"]
    for name, on, off, _what in DEVIATIONS:
        assert v[f"paper + {name}"] == ["preset=paper", f"{name}={on}"]
        assert v[f"default - {name}"] == [f"{name}={off}"]
    assert _turning(np.array([0.0, 0.5, 0.0, 3.1, -3.1])) == pytest.approx(1.0 + 3.1 + 2 * np.pi - 6.2)
