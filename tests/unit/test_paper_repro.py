"""Wang as published (fixed-step point, traditional baseline), the energy experiment's
presets, PAPF activity from a recording, and the horizon study's helpers."""

from pathlib import Path

import numpy as np
import pytest

from common.errors import ConfigError
from nodes.planner.wang.strategy import WangAPFParams, traditional_force
from papf.experiments.energy import EnergyExperiment, plan, validate
from papf.experiments.paper_study import DEVIATIONS, READINGS, _turning, _variants
from papf.offline.run import simulate
from papf.offline.wang_step import PointParams, fixed_step
from worlds import parse_world


def _world(obstacles, goal=(10.0, 0.0)):
    return parse_world({"name": "t", "description": "t", "robot": {"start": [0, 0, 0]},
                        "goal": {"position": list(goal), "tolerance": 0.25},
                        "obstacles": [{"kind": "cylinder", "center": list(c), "radius": r}
                                      for c, r in obstacles]})


def test_traditional_force_is_eqs_2_and_4_by_hand():
    table1 = WangAPFParams(k_att=10.0, k_rep_l=2.0, lidar_points=1, rho_0=20.0)   # the fixed step's
    f = traditional_force(np.zeros(2), np.array([3.0, 4.0]), np.array([[0.0, -0.5]]), table1)
    rep = 2.0 * (1 / 0.5 - 1 / 20.0) / 0.25            # K_rep (1/rho - 1/rho_0) / rho^2, away
    np.testing.assert_allclose(f, [30.0, 40.0 + rep])
    wp = WangAPFParams(lidar_points=1)
    g = traditional_force(np.zeros(2), [1.0, 0.0], np.array([[0.0, 0.25], [0.0, 0.6]]), wp)
    np.testing.assert_allclose(g, [10.0, -2.0 * (4.0 - 2.0) / 0.0625])   # 0.6 m: beyond rho_0


def test_fixed_step_walks_half_units_and_reaches_a_free_target():
    r = fixed_step(_world([((5.0, 3.0), 0.2)]), "traditional")
    assert r.outcome == "reached" and r.cycles == 20 and r.motion == "fixed-step"
    np.testing.assert_allclose(np.linalg.norm(np.diff(r.path, axis=0), axis=1), 0.5)


def test_fixed_step_collides_with_an_obstacle_on_the_line_and_fails_after_j():
    r = fixed_step(_world([((5.0, 0.0), 0.3)]), "traditional")
    assert r.outcome == "collision" and r.min_clearance_m < 0 and r.collisions == 1
    stuck = fixed_step(_world([], goal=(10.0, 0.0)), "traditional", PointParams(iterations=5))
    assert stuck.outcome == "failed" and stuck.cycles == 5


def test_fixed_step_results_are_in_metres_with_the_map_scale():
    """3-D worlds are stored 0.1 to metres: the walk's 0.5-unit steps are 0.05 m of path."""
    r = simulate("wang-3d-fig9", "wang", motion="fixed-step")
    assert r.units_per_m == 10.0 and r.planner == "wang" and r.outcome == "reached"
    np.testing.assert_allclose(np.linalg.norm(np.diff(r.path, axis=0), axis=1), 0.05)
    assert r.summary()["cycles"] == r.cycles == r.path.shape[0] - 1


def test_fixed_step_takes_only_wangs_planners_and_no_settings():
    with pytest.raises(ConfigError, match="valid"):
        simulate(_world([]), "apf", motion="fixed-step")
    with pytest.raises(ConfigError, match="do not apply"):
        simulate(_world([]), "wang", params=["preset=paper"], motion="fixed-step")
    with pytest.raises(ConfigError, match="motion"):
        simulate(_world([]), "wang", motion="teleport")


def test_fixed_step_refuses_boxes_and_unknown_methods():
    with pytest.raises(ConfigError, match="round obstacles"):
        fixed_step("papf-test-1", "traditional")
    with pytest.raises(ConfigError, match="valid"):
        fixed_step(_world([]), "magic")


def test_energy_experiment_runs_a_paper_variant_only_where_it_differs(tmp_path):
    exp = EnergyExperiment(out=tmp_path, runs=2, planners=("apf", "papf"), presets=("default", "paper"))
    names = [s.path.name for s in plan(exp)]
    assert names == ["apf-1.mcap", "apf-2.mcap", "papf-1.mcap", "papf-2.mcap",
                     "papf-paper-1.mcap", "papf-paper-2.mcap"]
    with pytest.raises(ConfigError, match="presets"):
        validate(EnergyExperiment(out=tmp_path, presets=("fast",)))


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


def test_new_worlds_load():
    from worlds import load_world

    for name in ("energy-empty", "energy-blocking", "papf-horizon", "wang-table1-fig5", "wang-table1-fig7"):
        w = load_world(name)
        assert w.goal[:2] in ((10.0, 0.0), (7.0, 0.0), (10.5, 8.0))
    assert len(load_world("wang-table1-fig5").obstacles) == 20
    assert not load_world("energy-empty").obstacles
    assert Path(__file__).parent.joinpath("..", "..", "worlds", "energy-blocking.toml").exists()


def test_cases_study_writes_a_summary_row_per_case_and_world(tmp_path, monkeypatch):
    import csv

    from papf.experiments import doc_cases

    monkeypatch.setitem(doc_cases.STUDIES, "tiny", [
        doc_cases.Case("apf", "apf", ("papf-test-4",)),
        doc_cases.Case("two", "papf", ("papf-test-4", "papf-test-4"), ("d_q=1.0",), group_by_world=False)])
    doc_cases.run_cases(tmp_path, ["tiny"])
    rows = list(csv.DictReader((tmp_path / "tiny.csv").open()))
    assert [(r["case"], r["world"], r["mode"]) for r in rows] == [
        ("apf", "papf-test-4", "offline"), ("two", "papf-test-4 papf-test-4", "offline")]
    assert rows[0]["reached"] == "0/1" and rows[0]["outcomes"] == "stagnated"   # APF fails Test IV
    assert rows[1]["reached"] == "2/2" and "-" not in rows[1]["duration_s"]       # deterministic: one value
    assert len(list(csv.DictReader((tmp_path / "cases-runs.csv").open()))) == 3
    assert doc_cases._span([1.0, float("nan"), 2.04], 1) == "1.0-2.0" and doc_cases._span([], 1) == ""
