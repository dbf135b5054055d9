"""The energy experiment's journal keeps a run's figures exact: a resumed experiment compares
them with the recordings (papf.report.metrics.REPRODUCE_TOL, 1e-9 relative) and must not call
its own runs mismatches (it exited 6 when the journal held the JSON's 6 decimals)."""

from __future__ import annotations

from papf.experiments.energy import (
    EXACT_FIGURES,
    EnergyExperiment,
    RunSpec,
    _resumed,
    _spec_key,
    journal_entry,
)
from papf.experiments.journal import Journal
from papf.launch.outcome import RunResult
from papf.report.metrics import differences_from_live


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
