"""The energy report from recordings: per-run metrics, re-metering, files, errors."""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest

from common.errors import ConfigError, PapfError, RecordingError
from common.units import NS_PER_S as NS
from nodes.energy_meter.core import EnergyMeter
from nodes.energy_meter.models import B_W, F_V_NM, MASS_KG, P_S_W, WHEEL_RADIUS_M
from nodes.recorder.writer import RunWriter
from papf.cli.report import finite
from papf.recording.reader import Recording
from papf.report import build_report, remeter_file, run_metrics
from papf.report.metrics import NO_OUTCOME, heading_oscillations, smoothness
from schemas import Event
from tests.support.recordings import SPEED, write_synthetic

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


# -- pure helpers -------------------------------------------------------------------------------
def test_heading_oscillations_counts_swings_beyond_the_threshold():
    assert heading_oscillations(np.array([0.0, 0.2, 0.05, -0.3, -0.2, 0.15, 0.01])) == 2
    assert heading_oscillations(np.array([0.05, -0.05, 0.09, -0.09])) == 0   # below 0.1 rad/s
    assert heading_oscillations(np.array([0.5, 0.6, 0.4])) == 0              # one-sided turn
    assert heading_oscillations(np.array([])) == 0


def test_smoothness_of_ramps_is_hand_computable():
    t = np.arange(0, 201) * 0.02                   # 4 s at 50 Hz
    c, k = 0.3, 0.2                                # w = c t (beta = c), v = k t^2 / 2 (jerk = k)
    ang, jerk = smoothness(t, 0.5 * k * t**2, c * t)
    assert ang == pytest.approx(c**2 * 4.0, rel=1e-9)
    assert jerk == pytest.approx(k**2 * (4.0 - 0.02), rel=1e-9)   # midpoints span T - dt
    assert smoothness(t, np.full_like(t, 0.4), np.zeros_like(t)) == (0.0, 0.0)


# -- metrics on a synthetic recording -----------------------------------------------------------
def test_metrics_of_a_synthetic_recording(tmp_path):
    path = tmp_path / "apf-1.mcap"
    meter = write_synthetic(path)
    m = run_metrics(path)
    assert (m.outcome, m.planner, m.world, m.seed) == ("reached", "apf", "energy", 1)
    assert m.t_end_s == pytest.approx(2.0)
    assert m.duration_s == pytest.approx(2.0 - 0.02)            # first motion at k = 1
    assert m.path_length_m == pytest.approx(SPEED * 2.0, rel=1e-12)   # only up to t_end
    # eq. (6) by hand: P_s always; B, friction (mean |v| of each interval) and the kinetic
    # energy of the first interval while moving
    dt = 0.02
    friction = 2 * F_V_NM / WHEEL_RADIUS_M * (0.5 * SPEED * dt + SPEED * (2.0 - dt))
    energy = P_S_W * 2.0 + B_W * 2.0 + friction + 0.5 * MASS_KG * SPEED**2
    assert m.energy_J == pytest.approx(energy, rel=1e-9)
    assert m.mean_power_W == pytest.approx(energy / 2.0, rel=1e-9)
    # charge: what the meter gave at t_end, exactly
    expected = EnergyMeter("paper")
    states = [s for s in (expected.feed(x) for x in _odom_wheels(path)) if s is not None]
    at_end = [s for s in states if s.stamp_ns <= 2 * NS][-1]
    assert m.charge_mAh == at_end.charge_used_mAh
    assert m.charge_mAh > 0 and meter.battery.charge_used_mAh > m.charge_mAh   # it went on
    assert (m.live_charge_mAh, m.remeter_diff_mAh) == (at_end.charge_used_mAh, 0.0)
    assert (m.ang_accel_sq, m.jerk_sq, m.heading_oscillations) == (0.0, 0.0, 0)
    assert m.series is not None and m.series.t_s[-1] == pytest.approx(2.0)


def _odom_wheels(path):
    with Recording(path) as rec:
        return [msg for _k, msg, _t in rec.messages(["rosbot/odom", "rosbot/wheels"])]


def test_remetering_with_the_other_model_changes_the_charge(tmp_path):
    path = tmp_path / "run.mcap"
    write_synthetic(path, model="paper")
    paper, motor = run_metrics(path), run_metrics(path, energy_model="motor")
    assert motor.energy_model == "motor" and motor.live_model == "paper"
    assert motor.charge_mAh != paper.charge_mAh
    assert remeter_file(path, "motor")[-1].model == "motor"


def test_outcomes_from_the_recording(tmp_path):
    write_synthetic(tmp_path / "none.mcap", outcome=None)
    m = run_metrics(tmp_path / "none.mcap")
    assert m.outcome == NO_OUTCOME and m.t_end_s == pytest.approx(120 * 0.02)
    write_synthetic(tmp_path / "timeout.mcap", outcome=None, meta={"timeout_s": "1.5"})
    m = run_metrics(tmp_path / "timeout.mcap")
    assert (m.outcome, m.t_end_s) == ("timeout", 1.5)
    assert m.path_length_m == pytest.approx(SPEED * 1.5)
    write_synthetic(tmp_path / "cut.mcap", outcome=None, meta={"timeout_s": "300"})
    m = run_metrics(tmp_path / "cut.mcap")       # ends before outcome and timeout: lost its end
    assert m.outcome == "incomplete" and "2.40 s" in m.reason
    path = tmp_path / "collision.mcap"
    write_synthetic(path)
    with RunWriter(tmp_path / "c.mcap", {"planner": "apf", "namespace": "rosbot"}) as w, \
            Recording(path) as rec:
        for raw in rec.raw():
            w.write(raw.key, raw.data)
        w.write_message("rosbot/events", Event(stamp_ns=NS, kind="collision", source="sim"))
    m = run_metrics(tmp_path / "c.mcap")
    assert (m.outcome, m.t_end_s, m.collisions) == ("collision", 1.0, 1)


def test_truncated_recording_names_papf_recover(tmp_path):
    path = tmp_path / "apf-1.mcap"
    write_synthetic(path)
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    with pytest.raises(RecordingError, match="papf recover"):
        run_metrics(path)
    with pytest.raises(RecordingError, match="papf recover"):
        build_report([tmp_path], tmp_path / "out")


def test_report_files(tmp_path):
    runs = tmp_path / "runs"
    runs.mkdir()
    for planner, speed in (("apf", 0.4), ("papf", 0.5)):
        for k in (1, 2):
            write_synthetic(runs / f"{planner}-{k}.mcap", planner, seed=k, speed=speed + 0.01 * k)
    report = build_report([runs], tmp_path / "out")
    out = tmp_path / "out"
    names = {"report.md", "report.csv", "report.html", "trajectories.png", "charge.png",
             "motion.png", "mind.png"}
    assert {p.name for p in report.files} == names
    for png in ("trajectories.png", "charge.png", "motion.png"):
        assert (out / png).read_bytes()[:8] == PNG_MAGIC
        import matplotlib.image as mpimg
        assert mpimg.imread(out / png).shape[0] > 100
    md = (out / "report.md").read_text()
    for png in ("trajectories.png", "charge.png", "motion.png"):
        assert f"]({png})" in md
    assert "−21.4 %" in md and "PAPF vs APF" in md
    rows = list(csv.DictReader(open(out / "report.csv")))
    assert [r["row"] for r in rows] == ["run"] * 4 + ["mean", "sd"] * 2
    runs_rows = [r for r in rows if r["row"] == "run"]
    assert [r["file"] for r in runs_rows] == ["apf-1.mcap", "apf-2.mcap", "papf-1.mcap",
                                              "papf-2.mcap"]
    apf = report.summary("apf").stats["charge_mAh"]
    mean_row = next(r for r in rows if r["row"] == "mean" and r["planner"] == "apf")
    assert float(mean_row["charge_mAh"]) == apf.mean
    charges = [float(r["charge_mAh"]) for r in runs_rows[:2]]
    assert apf.mean == pytest.approx(np.mean(charges)) and apf.sd == pytest.approx(
        np.std(charges, ddof=1))
    # the same files give the same report
    again = build_report([runs / "papf-2.mcap", runs], tmp_path / "again")
    assert (tmp_path / "again" / "report.csv").read_text() == (out / "report.csv").read_text()
    assert len(again.runs) == 4


def test_cli_report_and_experiment_options(tmp_path, capsys):
    from papf.cli import build_parser

    write_synthetic(tmp_path / "apf-1.mcap")
    parser = build_parser()
    args = parser.parse_args(["report", str(tmp_path), "--energy-model", "motor", "--json"])
    assert args.func(args) == 0
    assert '"energy_model": "motor"' in capsys.readouterr().out
    assert (tmp_path / "report-motor.md").is_file()       # re-metered: files of its own
    assert not (tmp_path / "report.md").exists()
    args = parser.parse_args(["experiment", "energy", "--runs", "2", "--planners", "apf,papf",
                              "--out", str(tmp_path / "x"), "--seed", "7"])
    assert (args.runs, args.planners, args.seed) == (2, "apf,papf", 7)
    args = parser.parse_args(["report", str(tmp_path / "nothing-here")])
    with pytest.raises(PapfError, match="nothing-here"):
        args.func(args)
    with pytest.raises(ConfigError, match="paper, motor"):
        build_report([tmp_path], energy_model="magic")


def test_report_groups_worlds_and_names_model_and_pose_source(tmp_path):
    runs = tmp_path / "runs"
    runs.mkdir()
    for world, speed in (("energy", 0.4), ("open", 0.6)):
        for planner in ("apf", "papf"):
            write_synthetic(runs / f"{world}-{planner}.mcap", planner, seed=1,
                            speed=speed + (0.05 if planner == "papf" else 0.0),
                            meta={"world": world})
    report = build_report([runs], tmp_path / "out")
    assert [(s.world, s.planner, s.runs) for s in report.summaries] == [
        ("energy", "apf", 1), ("energy", "papf", 1), ("open", "apf", 1), ("open", "papf", 1)]
    energy_apf = next(r for r in report.runs if (r.world, r.planner) == ("energy", "apf"))
    assert report.summary("apf", "energy").stats["charge_mAh"].mean == energy_apf.charge_mAh
    names = {p.name for p in report.files}
    assert {"trajectories-energy.png", "trajectories-open.png", "motion-energy.png",
            "motion-open.png", "mind-energy.png", "mind-open.png", "charge.png", "report.md",
            "report.csv", "report.html"} == names
    md = (tmp_path / "out" / "report.md").read_text()
    assert md.count("## World `") == 2 and "never averaged together" in md
    assert "energy model: paper (as the live meter ran)" in md
    assert "pose: ground truth (sim/pose)" in md and "charge [mAh, paper model]" in md
    rows = list(csv.DictReader(open(tmp_path / "out" / "report.csv")))
    means = [(r["world"], r["planner"]) for r in rows if r["row"] == "mean"]
    assert means == [("energy", "apf"), ("energy", "papf"), ("open", "apf"), ("open", "papf")]


def test_report_takes_the_live_model_and_names_unknown_seed_and_odometry(tmp_path):
    # a laptop-profile recording of old: no seed, no energy_model in the metadata, no ground truth
    write_synthetic(tmp_path / "robot.mcap", model="paper", meta={"seed": None,
                                                                  "energy_model": None},
                    ground_truth=False)
    m = run_metrics(tmp_path / "robot.mcap")
    assert (m.energy_model, m.live_model, m.pose_source, m.seed) == ("paper", "paper", "odom", -1)
    assert m.remeter_diff_mAh == 0.0                  # the live meter, reproduced
    report = build_report([tmp_path], tmp_path / "out")
    md = (tmp_path / "out" / "report.md").read_text()
    assert "pose: odometry" in md and "| robot.mcap | apf | ? |" in md
    again = build_report([tmp_path / "robot.mcap"], tmp_path / "out", energy_model="motor")
    assert again.suffix == "-motor" and (tmp_path / "out" / "report-motor.md").is_file()
    assert (tmp_path / "out" / "report.md").read_text() == md       # not overwritten
    assert {p.name for p in again.files} >= {"charge-motor.png", "trajectories-motor.png"}
    assert "re-metered; the live meter ran paper" in (tmp_path / "out" / "report-motor.md").read_text()
    assert report.runs[0].charge_mAh != again.runs[0].charge_mAh


def test_report_refuses_to_replace_an_earlier_report_unless_forced(tmp_path):
    from common.outfiles import OutputError
    from papf.report import build_report
    from tests.support.recordings import write_synthetic

    runs = tmp_path / "runs"
    runs.mkdir()
    write_synthetic(runs / "apf-1.mcap", "apf", seed=1, speed=0.4)
    out = tmp_path / "out"
    out.mkdir()
    (out / "report.md").write_text("the user's notes")
    with pytest.raises(OutputError, match=r"already holds a report \(report.md\); use --force"):
        build_report([runs], out)
    assert sorted(p.name for p in out.iterdir()) == ["report.md"]     # nothing moved
    assert (out / "report.md").read_text() == "the user's notes"
    (out / "charge.png").symlink_to(runs / "apf-1.mcap")   # a name that is an input
    with pytest.raises(OutputError, match="is the input"):
        build_report([runs], out, force=True)
    (out / "charge.png").unlink()
    build_report([runs], out, force=True)
    assert (out / "report.md").read_text() != "the user's notes"


def test_report_json_has_no_nan():
    assert json.dumps(finite({"a": math.nan, "b": [math.inf, 1.0]}), allow_nan=False) == \
        '{"a": null, "b": [null, 1.0]}'


def _runs(tmp_path):
    from tests.support.recordings import write_synthetic

    runs = tmp_path / "runs"
    runs.mkdir()
    for planner in ("apf", "papf"):
        write_synthetic(runs / f"{planner}-1.mcap", planner, seed=1)
    return runs


def test_report_refuses_an_existing_report_before_computing_anything(tmp_path, monkeypatch, capsys):
    from papf.cli import main
    from papf.report import report as report_module

    runs = _runs(tmp_path)
    (runs / "report.md").write_text("the user's own notes\n")

    def no_work(*_a, **_k):
        raise AssertionError("computed before the output check")

    monkeypatch.setattr(report_module, "collect", no_work)
    assert main(["report", str(runs)]) == 2
    err = capsys.readouterr().err
    assert f"{runs} already holds a report (report.md); use --force" in err
    assert (runs / "report.md").read_text() == "the user's own notes\n"
    assert sorted(p.name for p in runs.iterdir()) == ["apf-1.mcap", "papf-1.mcap", "report.md"]


def test_report_writes_one_self_contained_html_file(tmp_path):
    import re

    from papf.report import build_report

    runs = _runs(tmp_path)
    report = build_report([runs], tmp_path / "out")
    page = (tmp_path / "out" / "report.html")
    assert page in report.files
    text = page.read_text(encoding="utf-8")
    assert text.startswith("<!DOCTYPE html>") and "<table>" in text and "PAPF vs APF" in text
    sources = re.findall(r'<img src="([^"]*)"', text)
    assert len(sources) == 4 and all(s.startswith("data:image/png;base64,") for s in sources)
    assert "<script" not in text


def test_report_html_shows_a_recorded_text_as_text(tmp_path):
    from papf.report.html import report_html

    page = report_html("# r\n\nworld <script>alert(1)</script>\n", {}, "t<b>")
    assert "<script>" not in page and "&lt;script&gt;" in page and "<title>t&lt;b&gt;</title>" in page
