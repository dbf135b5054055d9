"""`papf experiment energy`: one real run through the stack."""

from __future__ import annotations

import io

import pytest
from rich.console import Console

from papf.experiments.energy import EnergyExperiment, run_experiment
from tests.support.worlds import SHORT_WORLD


@pytest.mark.slow   # the slow tier (make test-quick leaves it out)
def test_one_real_run_through_the_stack(tmp_path):
    world = tmp_path / "short.toml"
    world.write_text(SHORT_WORLD)
    text = io.StringIO()
    res = run_experiment(EnergyExperiment(out=tmp_path / "exp", runs=1, planners=("apf",),
                                          world=str(world), timeout_s=40.0),
                         Console(file=text, width=200))
    assert res.results[0][1].outcome == "reached", res.results[0][1].reason
    assert (tmp_path / "exp" / "apf-1.mcap").is_file()
    assert res.mismatches == [] and res.exit_code == 0
    assert "apf-1" in text.getvalue()
