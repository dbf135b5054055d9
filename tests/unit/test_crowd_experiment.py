"""papf/experiments/crowd.py: the hall scenes, the summary, a small sweep."""

from __future__ import annotations

import csv
import math

import pytest

from common.errors import ConfigError
from papf.experiments.crowd import HALL_X, HALL_Y, START, crowd_scene, run_crowd, summarize


def test_scenes_are_seeded_valid_and_keep_people_apart():
    a, text = crowd_scene(10, 3)
    b, again = crowd_scene(10, 3)
    assert text == again and a == b and crowd_scene(10, 4)[1] != text
    assert len(a.people) == 10 and all(p.loop and len(p.route) == 2 for p in a.people)
    points = [p.start for p in a.people] + [p.route[0] for p in a.people]
    for i, (x, y) in enumerate(points):
        assert HALL_X[0] < x < HALL_X[1] and HALL_Y[0] < y < HALL_Y[1]
        assert math.hypot(x - START[0], y - START[1]) >= 0.7
        assert all(math.hypot(x - u, y - v) >= 0.7 for u, v in points[:i])
    with pytest.raises(ConfigError, match="hall takes"):
        crowd_scene(99, 0)


def test_summary_rates_and_means():
    rows = [{"planner": "p", "people": 5, "outcome": o, "duration_s": d, "path_length_m": 8.0,
             "min_separation_m": s, "discomfort_s": 1.0, "intrusions": 2,
             "irregularity_rad_per_m": 0.5}
            for o, d, s in (("reached", 80.0, 0.2), ("reached", 90.0, 0.4),
                            ("collision", 10.0, 0.0), ("stagnated", 50.0, ""))]
    (row,) = summarize(rows, by="people")
    assert (row["runs"], row["reached"], row["collision"], row["stagnated"]) == (4, 50.0, 25.0, 25.0)
    assert row["time_s"] == 85.0                       # successful runs only
    assert row["time_s_ci"] == pytest.approx(12.706 * 5.0 * 2 ** 0.5 / 2 ** 0.5, abs=1e-3)
    assert row["min_separation_m"] == pytest.approx(0.2)   # the runs that met someone
    assert (row["reached_lo"], row["reached_hi"]) == (15.0, 85.0)   # Wilson, 2 of 4


def test_a_small_sweep_writes_its_files(tmp_path):
    summary = run_crowd(tmp_path, planners=["apf", "orca"], people=[0, 3], seeds=[0],
                        timeout_s=8, progress=False, scenes=("hall", "groups", "replay"))
    assert [(r["planner"], r["scene"]) for r in summary] == [
        (p, s) for p in ("apf", "orca") for s in ("hall-0", "hall-3", "groups",
                                                 "replay-walkers-hall")]
    with (tmp_path / "crowd.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 8 and rows[0]["min_separation_m"] == ""   # nobody to meet
    for k in ("intimate_s", "personal_n", "group_intrusions", "min_ttc_s",
              "collisions_person_by_person", "people_time_ext_s"):
        assert k in rows[0]
    for name in ("crowd.md", "crowd-summary.csv", "crowd.png", "crowd-scenes.png",
                 "worlds/crowd-3-0.toml", "worlds/crowd-groups-0.toml",
                 "worlds/crowd-replay-walkers-hall-0.toml"):
        assert (tmp_path / name).is_file()
    again = run_crowd(tmp_path, planners=["apf", "orca"], people=[0, 3], seeds=[0],
                      timeout_s=8, progress=False, scenes=("hall", "groups", "replay"))
    assert again == summary                            # from the journal, the same


@pytest.mark.parametrize("argv, says", [
    (["--people", "0,99"], "--people '0,99': comma-separated whole numbers 0-20"),
    (["--people", "five"], "--people 'five'"),
    (["--runs", "0"], "--runs=0: must be an integer in [1, 10000]"),
    (["--planners", "nope"], "unknown ['nope']"),
    (["--scenes", "hall,mall"], "--scenes 'hall,mall': comma-separated, of hall, groups, replay"),
    (["--replay", "no-such.txt"], "track file"),
    (["--scenes", "hall", "--replay", "x.txt"], "add replay to --scenes"),
    (["--worlds", "wang-3d-fig9"], "not a 2-D world of ROSbots"),
    (["--worlds", "no-such-world"], "no packaged world named 'no-such-world'"),
])
def test_bad_arguments_exit_2_with_one_line_before_any_run(argv, says, tmp_path, capsys):
    from papf.cli import main

    try:
        code = main(["experiment", "crowd", "--out", str(tmp_path / "o"), *argv])
    except SystemExit as exc:   # argparse's check of the option's type
        code = exc.code
    assert code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and says in err[0]
    assert not (tmp_path / "o").exists()


def test_the_groups_scene_has_standing_groups_in_the_way_and_a_walking_pair():
    from papf.experiments.crowd_scenes import groups_scene
    from worlds.checks import check_runnable

    a, text = groups_scene(2)
    assert groups_scene(2)[1] == text and groups_scene(3)[1] != text
    check_runnable(a)
    standing = [g for g in a.groups if g.standing(a.people)]
    walking = [g for g in a.groups if not g.standing(a.people)]
    assert len(standing) == 2 and len(walking) == 1 and len(walking[0].members) == 2
    centre = sum(a.people[i].start[1] for i in standing[0].members) / 3
    assert abs(centre) <= 0.6 + 1e-9                  # the first is in the robot's way


def test_a_replay_scene_crosses_a_foreign_files_span(tmp_path):
    from papf.experiments.crowd_scenes import replay_scene

    f = tmp_path / "eth.txt"
    f.write_text("0 1 -2.0 5.0\n10 1 6.0 7.0\n0 2 1.0 6.0\n10 2 1.0 4.0\n")
    w, _ = replay_scene(f, 0)
    assert w.start[:2] == (-1.0, 5.5) and w.goal == (5.0, 5.5) and not w.obstacles
    assert replay_scene(f, 1)[0].people_replay[0].from_s == 20.0


def test_crowd_keeps_each_finished_run_and_resumes_after_an_interrupt(tmp_path, monkeypatch):
    from papf.experiments import crowd

    real, calls = crowd.run_crowd_job, []

    def interrupted_second(job):
        calls.append(job.people)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return real(job)

    monkeypatch.setattr(crowd, "run_crowd_job", interrupted_second)
    with pytest.raises(KeyboardInterrupt):
        crowd.run_crowd(tmp_path, planners=["apf"], people=[0, 2], seeds=[0], timeout_s=5)
    assert len(list((tmp_path / "runs").glob("*.json"))) == 1
    calls.clear()
    monkeypatch.setattr(crowd, "run_crowd_job", lambda job: calls.append(job.people) or real(job))
    crowd.run_crowd(tmp_path, planners=["apf"], people=[0, 2], seeds=[0], timeout_s=5)
    assert calls == [2]                  # the finished run was taken from its file
    rows = (tmp_path / "crowd.csv").read_text().splitlines()
    assert len(rows) == 3 and rows[1].split(",")[4] == "0"   # in job order (people)
