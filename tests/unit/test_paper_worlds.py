"""The papers' test worlds load and are sane; the experiment tables and CLI wiring work."""

import math
from pathlib import Path

import numpy as np
import pytest

from papf.cli import build_parser
from papf.experiments.paper_tests import (
    ARAPF_WORLDS,
    PAPER,
    PAPER_WORLDS,
    PAPF_WORLDS,
    WANG_WORLDS,
    acceptance,
    table_rows,
)
from papf.experiments.random_worlds import kind_of, summarize
from papf.experiments.trials import Trial, markdown_table
from papf.offline.unicycle import FootprintChecker
from papf.offline.world_gen import is_solvable
from worlds import load_world, packaged_worlds
from worlds.geometry import signed_distance

WANG_3D = [w for w in packaged_worlds() if w.startswith("wang-3d-")]


@pytest.mark.parametrize("name", packaged_worlds())
def test_every_packaged_world_loads(name):
    w = load_world(name)
    assert w.name == name and w.description and w.tolerance > 0


def test_the_paper_worlds_are_packaged():
    names = set(packaged_worlds())
    assert set(PAPER_WORLDS) <= names
    assert len(WANG_3D) >= 3


@pytest.mark.parametrize("name", PAPF_WORLDS)
def test_papf_worlds_use_the_table1_goal(name):
    w = load_world(name)
    assert w.goal == (2.2, 2.7) and w.start == (0.0, 0.0, 0.0)


def test_arapf_and_wang_goals_follow_the_papers():
    assert load_world("arapf-test-1").goal == (4.2, 0.0)
    assert load_world("arapf-test-2").goal == (4.2, 0.0)
    assert load_world("arapf-test-3").goal == (4.8, 3.6)
    for name in WANG_WORLDS:
        assert load_world(name).goal == (4.2, 3.2)          # (10.5, 8) x 0.4


@pytest.mark.parametrize("name", PAPER_WORLDS)
def test_2d_paper_worlds_are_solvable_with_free_start_and_goal(name):
    w = load_world(name)
    assert is_solvable(w)
    chk = FootprintChecker(w)
    try:
        assert chk.clearance(*w.start) > 0.1
    finally:
        chk.close()
    assert signed_distance(w, np.array([w.goal[:2]]))[0] > 0.15   # the robot fits at the goal


@pytest.mark.parametrize("name", WANG_3D)
def test_3d_worlds_are_spheres_with_free_start_and_goal(name):
    w = load_world(name)
    assert w.dims == 3 and len(w.start) == 3 and w.obstacles
    for ob in w.obstacles:
        assert ob.shape == "sphere" and len(ob.center) == 3
        for p in (w.start, w.goal):
            assert math.dist(p, ob.center) > ob.radius + 0.2


# -- tables ---------------------------------------------------------------------------
def trial(world, planner, outcome, duration, length, collisions=0):
    return Trial(world, planner, 0, "offline", outcome, duration, length, collisions)


def test_table_rows_give_the_change_against_apf_like_table2():
    trials = [trial("papf-test-1", "apf", "reached", 69.79, 4.50),
              trial("papf-test-1", "papf", "reached", 41.71, 4.13),
              trial("papf-test-4", "apf", "stagnated", 30.0, 1.0),
              trial("papf-test-4", "papf", "reached", 38.4, 3.77)]
    rows = table_rows(trials)
    assert rows[1][4] == "-40.2 %" and rows[1][6] == "-8.2 %"   # PAPF paper: 40.23 %, 8.29 %
    assert rows[3][4] == ""                                     # APF did not reach: no change
    assert rows[1][7:] == ["reached", "41.71", "4.13"]
    md = markdown_table(["a", "b"], [[1, "x|y"]])
    assert md.splitlines()[2] == "| 1 | x\\|y |"


def test_acceptance_sentences():
    trials = [trial(w, "papf", "reached", 40.0, 4.0) for w in PAPF_WORLDS]
    trials += [trial(w, "apf", "reached" if w[-1] in "1236" else "stagnated", 50.0, 4.2)
               for w in PAPF_WORLDS]
    text = " ".join(acceptance(trials))
    assert "6/6 PAPF-paper worlds, 0 collision" in text
    assert "APF's in 4/4 worlds" in text and "`stagnated` in 2/2" in text


def test_paper_reference_values():
    assert PAPER["papf-test-4"]["apf"].outcome == "fails"
    assert PAPER["papf-test-5"]["papf"].path_length_m == 3.87
    assert all(PAPER[w]["arapf"].outcome == "reached" for w in ARAPF_WORLDS)


def test_random_summary_rates():
    trials = [trial("rand-0-000-field", "apf", "reached", 1, 1),
              trial("rand-0-001-dead_end", "apf", "stagnated", 1, 1),
              trial("rand-0-002-gap", "apf", "collision", 1, 1, collisions=1),
              trial("rand-0-003-field", "apf", "reached", 1, 1)]
    assert kind_of("rand-0-001-dead_end") == "dead_end"
    (row,) = summarize(trials)
    assert row["worlds"] == 4 and row["reached"] == 50.0 and row["collision"] == 25.0
    assert row["collisions"] == 1 and row["reached_field"] == 100.0 and row["reached_gap"] == 0.0


# -- CLI wiring -----------------------------------------------------------------------
def test_plan_and_experiment_commands_parse():
    parser = build_parser()
    args = parser.parse_args(["experiment", "random", "--n", "3", "--stack"])
    assert args.n == 3 and args.mode == "stack" and args.func.__name__ == "cmd_random"
    args = parser.parse_args(["experiment", "paper-tests", "--offline", "--planners", "apf"])
    assert args.offline and args.func.__name__ == "cmd_paper_tests"
    args = parser.parse_args(["plan", "--world", "open", "--planner", "papf", "--plot", "x.png"])
    assert args.plot == "x.png" and args.func.__name__ == "cmd_plan"
    args = parser.parse_args(["experiment", "energy", "--runs", "2"])
    assert args.experiment == "energy" and args.runs == 2 and args.func.__name__ == "cmd_energy"


def test_new_worlds_load():
    from worlds import load_world

    for name in ("energy-empty", "energy-blocking", "papf-horizon", "wang-table1-fig5", "wang-table1-fig7"):
        w = load_world(name)
        assert w.goal[:2] in ((10.0, 0.0), (7.0, 0.0), (10.5, 8.0))
    assert len(load_world("wang-table1-fig5").obstacles) == 20
    assert not load_world("energy-empty").obstacles
    assert Path(__file__).parent.joinpath("..", "..", "worlds", "energy-blocking.toml").exists()
