"""The report names why its charge differs from the live figure of the same run."""

from __future__ import annotations

import dataclasses
import math

from papf.report.metrics import RunMetrics, live_difference


def _metrics(**kw) -> RunMetrics:
    base = dict(file="first.mcap", planner="papf", world="energy", seed=0, outcome="reached",
                reason="", t_end_s=100.96, duration_s=100.0, path_length_m=9.95,
                charge_mAh=25.27, energy_J=1100.0, mean_power_W=11.0, live_charge_mAh=25.27,
                live_energy_J=1100.0, live_stamp_s=100.96, live_model="motor",
                remeter_diff_mAh=0.0, energy_model="motor", pose_source="odom",
                ang_accel_sq=0.0, jerk_sq=0.0, heading_oscillations=0, collisions=0)
    return dataclasses.replace(RunMetrics(**base), **kw)


def test_agreeing_figures_need_no_word():
    assert live_difference(_metrics()) == ""
    assert live_difference(_metrics(energy_model="paper")) == ""   # re-metered: noted elsewhere
    assert live_difference(_metrics(live_charge_mAh=math.nan)) == ""


def test_a_difference_is_split_into_its_two_causes():
    text = live_difference(_metrics(charge_mAh=26.05, live_charge_mAh=25.27, live_stamp_s=98.0,
                                    remeter_diff_mAh=0.30))
    assert "26.05 mAh here vs 25.27 mAh live (+0.78)" in text
    assert "+0.48 mAh drawn between" in text and "(98.00 s) and the outcome (100.96 s)" in text
    assert "+0.30 mAh from re-metering" in text


def test_a_recording_without_metadata_started_mid_run(tmp_path):
    """``papf record`` without --meta, started 20 s into a run: said as such."""
    from nodes.recorder.writer import RunWriter
    from papf.report.metrics import UNKNOWN_WORLD, metadata_notes, run_metrics
    from schemas.messages import Clock, Odometry, PlannerStatus, WheelStates

    path = tmp_path / "session.mcap"
    with RunWriter(path) as w:
        for k in range(200):                        # 20 s .. 24 s at 50 Hz
            t = 20_000_000_000 + k * 20_000_000
            w.write_message("rosbot/clock", Clock(stamp_ns=t))
            w.write_message("rosbot/odom", Odometry(stamp_ns=t, x=2.0 + 0.002 * k, y=0.0,
                                                    yaw=0.0, v=0.1, w=0.0))
            w.write_message("rosbot/wheels", WheelStates(stamp_ns=t, speed=(1.2,) * 4,
                                                         torque=(0.05,) * 4))
        w.write_message("rosbot/planner/status", PlannerStatus(stamp_ns=t, state="reached"))
    m = run_metrics(path)
    assert m.world == UNKNOWN_WORLD and m.outcome == "partial"
    assert "starts at 20.00 s" in m.reason
    assert math.isclose(m.mean_power_W, m.energy_J / (m.t_end_s - 20.0), rel_tol=1e-9)
    notes = metadata_notes(m)
    assert any("world unknown" in n for n in notes) and any("first message" in n for n in notes)
    assert m.recorded_from_s == 20.0 and "recorded_from_s" not in m.row()
    said = " ".join(notes)
    assert "begun mid-run: it holds 20.00-" in said and "outcome partial" in said
    assert live_difference(dataclasses.replace(m, live_charge_mAh=99.0, live_model=m.energy_model)) == ""
