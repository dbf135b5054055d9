"""Sweeps on Dask (papf.experiments.sweep): the same CSV however the runs are spread over worker
processes."""

import csv
import os
import time

import pytest

from papf.experiments.paper_tests import run_paper_tests
from papf.experiments.random_worlds import run_random
from papf.experiments.sweep import SweepOptions, map_runs


def _square(x: int) -> int:
    return x * x


def _pid_after(seconds: float) -> int:
    time.sleep(seconds)
    return os.getpid()


def test_local_cluster_map_keeps_job_order():
    assert map_runs(_square, list(range(6)), SweepOptions(workers=2, progress=False)) == [
        x * x for x in range(6)]


def test_two_workers_are_two_other_processes():
    """--workers 2 really spreads: the runs happen in two worker processes, not here."""
    pids = map_runs(_pid_after, [0.5] * 4, SweepOptions(workers=2, progress=False))
    assert len(set(pids)) == 2 and os.getpid() not in pids


def _rows(path) -> list[dict]:
    with path.open(newline="") as fh:
        return list(csv.DictReader(fh))


@pytest.mark.slow   # the slow tier (make test-quick leaves it out)
def test_offline_random_sweep_same_csv_with_two_workers(tmp_path):
    for workers in (1, 2):
        run_random(tmp_path / f"w{workers}", n=2, seed=3, planners=("apf", "papf"),
                   mode="offline", timeout_s=15, progress=False, sweep=SweepOptions(workers))
    assert (tmp_path / "w1" / "random.csv").read_bytes() == (tmp_path / "w2" / "random.csv").read_bytes()
    rows = _rows(tmp_path / "w2" / "random.csv")   # two worlds x two planners, real runs
    assert len(rows) == 4 and all(float(r["duration_s"]) > 0 for r in rows)


@pytest.mark.slow   # the slow tier (make test-quick leaves it out)
def test_stack_sweep_same_csv_with_two_workers(tmp_path):
    """Two full-stack runs at once (own router ports and namespaces): the CSV of a
    sequential sweep, byte for byte, and every recording gathered here."""
    for workers in (1, 2):
        run_paper_tests(tmp_path / f"w{workers}", ("apf", "papf"), 0, "stack", ("papf-test-1",),
                        timeout_s=8.0, progress=False, sweep=SweepOptions(workers))
    one, two = (tmp_path / f"w{w}" / "paper-tests.csv" for w in (1, 2))
    assert one.read_bytes() == two.read_bytes()
    rows = _rows(two)   # both runs made and measured, not two empty tables
    assert [r["planner"] for r in rows] == ["apf", "papf"]
    assert all(r["outcome"] in ("reached", "timeout") and float(r["path_length_m"]) > 0.1
               for r in rows)
    assert sorted(p.name for p in (tmp_path / "w2" / "recordings").iterdir()) == [
        "papf-test-1-apf.mcap", "papf-test-1-papf.mcap"]
