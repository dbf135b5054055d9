"""`papf experiment energy`: plan (a paper preset run only where it differs), settings checks,
orchestration (with a stand-in run), and a journal that keeps a run's figures exact (a resumed
experiment must not call its own runs mismatches)."""

from __future__ import annotations

import io
from dataclasses import replace
from pathlib import Path

import pytest
from rich.console import Console

from common.errors import ConfigError
from papf.experiments.energy import (
    EXACT_FIGURES,
    EnergyExperiment,
    RunSpec,
    _resumed,
    _spec_key,
    journal_entry,
    plan,
    print_summary,
    run_experiment,
    validate,
)
from papf.experiments.journal import Journal
from papf.launch.outcome import RunResult
from papf.launch.run import resolve_run
from papf.report.metrics import differences_from_live
from tests.support.recordings import FakeRuns


def test_plan_names_files_and_seeds(tmp_path):
    specs = plan(EnergyExperiment(out=tmp_path, runs=3, planners=("apf", "papf"), seed=10))
    assert [s.path.name for s in specs] == ["apf-1.mcap", "apf-2.mcap", "apf-3.mcap",
                                            "papf-1.mcap", "papf-2.mcap", "papf-3.mcap"]
    assert [s.seed for s in specs] == [11, 12, 13, 11, 12, 13]   # k-th runs share their noise
    assert all(s.path.parent == tmp_path for s in specs)


@pytest.mark.parametrize(("change", "match"), [
    ({"runs": 0}, "at least 1"), ({"planners": ("apf", "nope")}, "nope.*valid: apf"),
    ({"planners": ()}, "empty"), ({"planners": ("apf", "apf")}, "twice"),
    ({"energy_model": "x"}, "motor, paper"), ({"timeout_s": 0.0}, "> 0"),
])
def test_bad_settings_are_refused_before_any_run(tmp_path, change, match):
    exp = replace(EnergyExperiment(out=tmp_path), **change)
    with pytest.raises(ConfigError, match=match):
        run_experiment(exp, Console(file=io.StringIO()), run_fn=pytest.fail)


def test_experiment_records_every_run_and_reports(tmp_path):
    out = tmp_path / "exp"
    fake, text = FakeRuns(), io.StringIO()
    console = Console(file=text, width=200)
    res = run_experiment(EnergyExperiment(out=out, runs=2, seed=4), console, run_fn=fake)
    assert [(c.planner, c.seed, Path(c.record).name) for c in fake.configs] == [
        ("apf", 5, "apf-1.mcap"), ("apf", 6, "apf-2.mcap"),
        ("papf", 5, "papf-1.mcap"), ("papf", 6, "papf-2.mcap")]
    cfg = fake.configs[0]
    assert cfg.world == "energy" and cfg.progress is False and cfg.port
    recorder = resolve_run(cfg).nodes["recorder"]    # the sim profile states the timeout
    assert "timeout_s=300" in recorder and "experiment=energy" in recorder
    # its runs share the cores: each waits 10 s for a command, not papf run's 2 s
    world = resolve_run(cfg).nodes["base_driver"]
    assert world[world.index("--lockstep-timeout") + 1] == "10"
    assert all(c.port for c in fake.configs)          # an explicit free port each run
    for name in ("report.md", "report.csv", "trajectories.png", "charge.png", "motion.png"):
        assert (out / name).is_file()
    assert res.mismatches == [] and res.exit_code == 0
    assert [s.reached for s in res.report.summaries] == [2, 2]
    assert text.getvalue().count("reached") >= 4          # one line per finished run
    print_summary(res, console)
    shown = text.getvalue()
    assert "PAPF vs APF charge: " in shown and "wall time" in shown


def test_report_that_disagrees_with_the_live_run_is_flagged(tmp_path):
    res = run_experiment(EnergyExperiment(out=tmp_path, runs=1, planners=("apf",)),
                         Console(file=io.StringIO()), run_fn=FakeRuns(charge_error=1e-3))
    assert res.mismatches and "charge_mAh" in res.mismatches[0] and res.exit_code == 6


def test_a_recording_that_lost_its_end_is_reported_not_run_again(tmp_path):
    fake, text = FakeRuns(cut_first=1), io.StringIO()
    res = run_experiment(EnergyExperiment(out=tmp_path, runs=1, planners=("apf",)),
                         Console(file=text, width=200), run_fn=fake)
    assert len(fake.configs) == 1                       # the recorder's ack makes files whole
    assert res.mismatches and res.exit_code == 6


def test_the_table_shows_its_units_piped_and_on_a_terminal(tmp_path):
    """"[mAh, motor]" and "[s]" are text: rich must not take them for style tags."""
    import re

    res = run_experiment(EnergyExperiment(out=tmp_path, runs=1, planners=("apf",)),
                         Console(file=io.StringIO()), run_fn=FakeRuns())
    for terminal in (False, True):
        text = io.StringIO()
        print_summary(res, Console(file=text, width=200, force_terminal=terminal))
        shown = re.sub(r"\x1b\[[0-9;]*m", "", text.getvalue())
        model = res.report.model
        for header in (f"charge [mAh, {model}]", f"energy [J, {model}]", "duration [s]",
                       "path [m]"):
            assert header in shown, (terminal, shown)


def test_a_report_the_experiment_did_not_make_is_refused_before_any_run(tmp_path):
    """Issue #35: output checks before work. The user's report.md in --out stops the
    experiment before its first run; the experiment's own report (its journal is there)
    is replaced when it runs again."""
    from common.outfiles import OutputError

    (tmp_path / "report.md").write_text("mine\n")
    with pytest.raises(OutputError, match="did not make"):
        run_experiment(EnergyExperiment(out=tmp_path, runs=1, planners=("apf",)),
                       Console(file=io.StringIO()), run_fn=pytest.fail)
    assert (tmp_path / "report.md").read_text() == "mine\n"
    out = tmp_path / "again"
    for _ in range(2):   # the second time: the runs come from the journal, the report is redone
        (out / "report.md").unlink(missing_ok=True)   # replaced, not refused, the second time
        run_experiment(EnergyExperiment(out=out, runs=1, planners=("apf",)),
                       Console(file=io.StringIO()), run_fn=FakeRuns())
        assert (out / "report.html").is_file() and (out / "report.md").is_file()


def _result() -> RunResult:
    return RunResult("reached", "papf", "energy", 0, duration_s=99.680000123456,
                     path_length_m=9.950115123456789, charge_mAh=23.946955456789,
                     energy_J=1066.4321987654, collisions=0, sim_time_s=99.78000001,
                     wall_time_s=3.14159265, run_id="00ff")


def test_a_resumed_run_has_the_figures_it_ended_with(tmp_path):
    exp = EnergyExperiment(out=tmp_path)
    spec = RunSpec("papf", 1, 0, tmp_path / "papf-1.mcap")
    spec.path.write_bytes(b"")                       # its recording is there
    live = _result()
    Journal(tmp_path).put(_spec_key(exp, spec), journal_entry(live))
    resumed = _resumed(Journal(tmp_path), exp, spec)
    assert resumed is not None
    assert {k: getattr(resumed, k) for k in EXACT_FIGURES} == \
        {k: getattr(live, k) for k in EXACT_FIGURES}
    assert differences_from_live("papf-1", resumed, live) == []


def test_the_json_alone_would_have_been_a_mismatch():
    """Why: the run's JSON rounds to 6 decimals, 1e-7 apart from the file's figure."""
    live = _result()
    rounded = RunResult(**{**live.__dict__, **{k: v for k, v in live.to_json().items()
                                               if k in EXACT_FIGURES}})
    assert differences_from_live("papf-1", rounded, live) != []


def test_energy_experiment_runs_a_paper_variant_only_where_it_differs(tmp_path):
    exp = EnergyExperiment(out=tmp_path, runs=2, planners=("apf", "papf"), presets=("default", "paper"))
    names = [s.path.name for s in plan(exp)]
    assert names == ["apf-1.mcap", "apf-2.mcap", "papf-1.mcap", "papf-2.mcap",
                     "papf-paper-1.mcap", "papf-paper-2.mcap"]
    with pytest.raises(ConfigError, match="presets"):
        validate(EnergyExperiment(out=tmp_path, presets=("fast",)))
