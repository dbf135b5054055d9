"""What every ``papf experiment`` shares: the journal keeps each finished run and ignores garbage
(papf/experiments/journal.py), a sweep resumes after an interrupt (papf/experiments/trials.py),
an ``--out`` that is a file is refused before any run."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from papf.cli.report import finite
from papf.experiments.journal import Journal, run_key
from worlds import load_world, world_path

SETTINGS = settings(max_examples=40, deadline=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture])


@pytest.mark.parametrize("experiment", [["crowd", "--people", "0", "--runs", "1"],
                                        ["random", "--n", "1"], ["traffic"], ["paper-tests"],
                                        ["energy", "--runs", "1"], ["wang"], ["cases"]])
def test_an_experiment_out_that_is_a_file_is_one_line_before_any_run(tmp_path, capsys, experiment):
    from papf.cli import main

    f = tmp_path / "afile"
    f.write_text("mine")
    assert main(["experiment", *experiment, "--out", str(f)]) == 2
    assert "is a file" in capsys.readouterr().err and f.read_text() == "mine"


@SETTINGS
@given(entries=st.dictionaries(st.text(max_size=8), st.floats(allow_nan=True), max_size=5))
def test_the_journal_gives_back_what_it_took_and_ignores_garbage(tmp_path_factory, entries):
    out = tmp_path_factory.mktemp("exp")
    j = Journal(out)
    key = run_key("world", "apf", 1)
    assert j.get(key) is None
    j.put(key, {"x": finite(entries)})
    assert Journal(out).get(key) == {"x": finite(entries)}
    (j.dir / f"{key}.json").write_text("{not json")
    assert Journal(out).get(key) is None
    (j.dir / f"{key}.json").write_text(json.dumps({"key": "other", "data": {}}))
    assert Journal(out).get(key) is None


def test_a_sweep_keeps_each_run_as_it_ends_and_resumes(tmp_path, monkeypatch):
    from papf.experiments import trials

    world = load_world("open")
    jobs = [trials.trial_job(world, world_path("open"), planner="apf", seed=s, mode="offline",
                             timeout_s=1.0, index=s) for s in range(3)]
    made = []

    def fake_run(job):
        made.append(job.seed)
        if job.seed == 2 and len(made) == 3:
            raise KeyboardInterrupt   # Ctrl-C during the third run
        return trials.Trial(job.world.name, job.planner, job.seed, "offline", "reached", 1.5,
                            2.0, 0, path=np.array([[0.0, 0.0], [1.0, 0.5]])), None

    monkeypatch.setattr(trials, "run_job", fake_run)
    with pytest.raises(KeyboardInterrupt):
        trials.sweep_trials(jobs, None, False, "t", tmp_path)
    assert len(list((tmp_path / "runs").glob("*.json"))) == 2
    done = trials.sweep_trials(jobs, None, False, "t", tmp_path)
    assert made == [0, 1, 2, 2] and [t.seed for t in done] == [0, 1, 2]
    assert done[0].path.tolist() == [[0.0, 0.0], [1.0, 0.5]] and math.isnan(done[0].charge_mAh)
