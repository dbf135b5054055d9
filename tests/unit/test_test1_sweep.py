"""``papf experiment test1-sweep``: the APF-only calibration of papf-test-1's box."""

import csv
import math

from papf.cli import main as papf_main
from papf.experiments.test1_sweep import (
    APF_DURATION_S,
    APF_PATH_M,
    CALIBRATED,
    GOAL,
    OLD,
    box_center,
    box_clearance,
    choose,
    run_sweep,
    sweep_world,
)
from worlds import load_world


def row(side, along, offset, path, reached=3, runs=3, duration=APF_DURATION_S):
    return {"side_m": side, "along_m": along, "offset_m": offset, "runs": runs,
            "reached": reached, "path_mean_m": path, "duration_mean_s": duration}


def test_box_center_is_along_the_line_and_to_its_right():
    x, y = box_center(1.0, 0.0)
    assert math.isclose(math.hypot(x, y), 1.0, abs_tol=1e-3)
    assert math.isclose(x * GOAL[1] - y * GOAL[0], 0.0, abs_tol=1e-2)     # on the line
    x, y = box_center(1.0, 0.3)
    assert GOAL[0] * y - GOAL[1] * x < 0                                  # right of it


def test_the_packaged_world_holds_the_calibrated_box():
    ob = load_world("papf-test-1").obstacles[0]
    want = sweep_world(*CALIBRATED).obstacles[0]
    assert ob.shape == "box" and ob.size == want.size and ob.center == want.center
    assert sweep_world(*OLD).obstacles[0].center == (1.14, 1.161)      # the box before


def test_clearance_keeps_start_and_goal_free():
    assert box_clearance(0.5, 1.62, 0.15) > 1.0
    assert box_clearance(1.5, 1.2, 0.15) < 0.5


def test_choose_takes_the_nearest_path_and_breaks_ties_by_the_smallest_change():
    rows = [row(0.5, 1.62, 0.15, 3.9), row(1.3, 1.62, 0.15, APF_PATH_M + 0.01),
            row(0.9, 1.62, 0.15, APF_PATH_M - 0.02), row(0.7, 1.62, 0.15, APF_PATH_M, reached=2)]
    assert choose(rows)["side_m"] == 0.9            # within the tie of the best, nearer the old
    assert choose(rows, tie_m=0.0)["side_m"] == 1.3
    assert choose([row(0.5, 1.62, 0.15, 4.5, reached=0)]) is None


def test_choose_keeps_apf_duration_within_the_band_unless_asked_for_the_path_alone():
    rows = [row(1.5, 2.0, 0.3, APF_PATH_M, duration=1.38 * APF_DURATION_S),
            row(1.3, 2.0, 0.3, APF_PATH_M - 0.2, duration=1.09 * APF_DURATION_S),
            row(0.9, 2.0, 0.15, APF_PATH_M - 0.3, duration=APF_DURATION_S)]
    assert choose(rows)["side_m"] == 1.3
    assert choose(rows, duration_band_pct=None)["side_m"] == 1.5


def test_a_tiny_sweep_writes_its_tables(tmp_path):
    rows, chosen = run_sweep(tmp_path, sides=(0.5,), alongs=(1.62,), offsets=(0.15,), seeds=(0,),
                             timeout_s=3.0)
    assert chosen is None and rows[0]["reached"] == 0 and rows[0]["runs"] == 1
    with (tmp_path / "test1-sweep-runs.csv").open() as fh:
        (run,) = list(csv.DictReader(fh))
    assert run["outcome"] == "timeout" and run["seed"] == "0"
    assert "none qualifies" in (tmp_path / "test1-sweep.md").read_text()


def test_bad_seeds_are_a_usage_error(tmp_path, capsys):
    assert papf_main(["experiment", "test1-sweep", "--seeds", "a,b", "--out", str(tmp_path)]) == 2
    assert "--seeds" in capsys.readouterr().err


def test_a_sweep_run_again_takes_its_finished_runs_from_the_journal(tmp_path, monkeypatch):
    """Issue 31: the sweep is journalled like the other experiments (papf.experiments.journal)."""
    import papf.offline.run as offline

    grid = {"sides": (0.5,), "alongs": (1.62,), "offsets": (0.15,), "seeds": (0,),
            "timeout_s": 3.0}
    run_sweep(tmp_path, **grid)
    assert len(list((tmp_path / "runs").glob("*.json"))) == 1

    def no_simulation(*_a, **_k):
        raise AssertionError("a finished run was made again")

    monkeypatch.setattr(offline, "simulate", no_simulation)
    rows, _ = run_sweep(tmp_path, **grid)
    assert rows[0]["runs"] == 1
