"""The energy report of a real run re-meters to the live meter's figures."""

from __future__ import annotations

import math

from papf.recording.reader import Recording
from papf.report import build_report, remeter_file, run_metrics
from schemas import BatteryState
from tests.support.worlds import SHORT_WORLD


# -- a real run through the whole process stack -------------------------------------------------
def test_remetering_a_real_run_reproduces_the_live_meter_exactly(tmp_path):
    from papf.launch.run import RunConfig, run
    from papf.launch.supervisor import free_port

    world = tmp_path / "short.toml"
    world.write_text(SHORT_WORLD)
    path = tmp_path / "apf-1.mcap"
    result = run(RunConfig(world=str(world), planner="apf", seed=3, timeout_s=40.0,
                           record=str(path), port=free_port(), progress=False))
    assert result.outcome == "reached", result.reason
    with Recording(path) as rec:
        live = [m for _k, m, _t in rec.messages("rosbot/battery") if isinstance(m, BatteryState)]
    remetered = {s.stamp_ns: s for s in remeter_file(path, "motor")}
    assert len(live) > 100
    # every field, bit for bit; every sample of the run (up to its end instant T). The nodes
    # run on until run_ended reaches them, and the recorder records past T only what came
    # before it closed: a battery sample past T may be in it without its odometry
    end = round(result.sim_time_s * 1e9)
    assert all(remetered[b.stamp_ns] == b for b in live if b.stamp_ns <= end)
    assert all(remetered[b.stamp_ns] == b for b in live if b.stamp_ns in remetered)
    m = run_metrics(path)
    # the report's figures from the file alone are the live run's summary figures
    assert (m.outcome, m.duration_s, m.path_length_m) == (result.outcome, result.duration_s,
                                                          result.path_length_m)
    assert (m.charge_mAh, m.energy_J) == (result.charge_mAh, result.energy_J)
    assert m.remeter_diff_mAh == 0.0 and not math.isnan(m.live_charge_mAh)
    report = build_report([path], tmp_path / "report")
    assert (tmp_path / "report" / "report.md").is_file() and report.runs[0].outcome == "reached"
