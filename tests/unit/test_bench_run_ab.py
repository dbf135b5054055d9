"""bench run_ab's summaries and TreeCPU's per-process names (no bus)."""

from __future__ import annotations

import os
import subprocess
import sys
import time

import pytest

from bench.bench_run_ab import process_rows, summary
from bench.proc_cpu import TreeCPU

FIG = {"outcome": "reached", "sim_time_s": 10.0, "charge_mAh": 1.0}


def _run(cpu, procs, figures=FIG):
    return {"planner": "apf", "timeout_s": 300.0, "command_wall_s": 2.0, "run_wall_s": 1.5,
            "cpu_s": cpu, "load_1min": 1.0, "figures": dict(figures), "processes": procs}


def test_summary_compares_figures_with_the_other_side_and_gives_cpu_per_cycle():
    runs = [_run(3.0, {}), _run(5.0, {})]
    row = summary("after", runs, reference=FIG)
    assert row["same_figures"] and row["cpu_med_s"] == 4.0
    assert row["cpu_ms_per_cycle"] == 40.0          # 4 s over 100 cycles of 100 ms
    assert row["sim_over_run_wall_med"] == round(10.0 / 1.5, 1)   # sim over the JSON's wall
    assert not summary("after", runs, reference={**FIG, "charge_mAh": 1.1})["same_figures"]


def test_process_rows_are_medians_per_process_with_short_names():
    runs = [_run(3.0, {"papf": 1.0, "nodes.planner": 2.0}),
            _run(5.0, {"papf": 3.0, "nodes.planner": 4.0, "nodes.recorder": 1.0})]
    rows = {r["process"]: r for r in process_rows("after", runs)}
    assert set(rows) == {"launcher", "planner", "recorder"}
    assert rows["planner"]["cpu_med_s"] == 3.0 and rows["planner"]["cpu_ms_per_cycle"] == 30.0
    assert rows["recorder"]["cpu_med_s"] == 0.5      # 0 in the run that did not start it


@pytest.mark.skipif(not os.path.isdir("/proc"), reason="reads /proc")
def test_tree_cpu_names_a_grandchild_by_its_module():
    child = ("import subprocess, sys; subprocess.run([sys.executable, '-m', 'timeit', '-n', '1', "
             "'-r', '1', 'import time; time.sleep(0.6)'], check=True)")
    with TreeCPU(period_s=0.02) as cpu:
        subprocess.run([sys.executable, "-c", child], check=True, capture_output=True)
    assert "timeit" in cpu.per_process()


def test_tree_cpu_charges_the_root_only_with_the_cpu_used_inside_the_block():
    """A bench that runs the stack in its own process, again and again, reports each run's
    launcher CPU, not the sum of every run so far."""
    def spin(s):
        end = time.process_time() + s
        while time.process_time() < end:
            pass

    spin(0.6)                                   # before the block: not the block's
    with TreeCPU(period_s=0.02) as cpu:
        spin(0.2)
    launcher = cpu.per_process()["launcher"]["cpu_s"]
    assert 0.1 < launcher < 0.5, launcher
