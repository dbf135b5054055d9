"""Sweeps (papf.experiments.sweep): options and the sequential map."""

import pytest

from common.errors import ConfigError
from papf.experiments.sweep import SweepOptions, map_runs, run_namespace


def _square(x: int) -> int:
    return x * x


def test_options_name_what_is_wrong():
    for bad, what in ((SweepOptions(workers=0), "--workers"),
                      (SweepOptions(scheduler="10.0.0.5:8786"), "tcp://HOST:PORT"),
                      (SweepOptions(workers=2, scheduler="tcp://h:8786"), "exclude")):
        with pytest.raises(ConfigError, match=what):
            bad.validate()
    assert SweepOptions(scheduler="tcp://10.0.0.5:8786").distributed
    assert not SweepOptions().distributed


def test_sequential_map_keeps_job_order_and_prints_a_line_per_run(capsys):
    assert map_runs(_square, [3, 1, 2], SweepOptions(progress=False)) == [9, 1, 4]
    assert capsys.readouterr().err.count("\n") == 3          # piped: one line per run
    assert len({run_namespace(i) for i in range(100)}) == 100
