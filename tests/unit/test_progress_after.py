"""StepProgress(after_s=...): a quick job prints nothing, a slow one says what it is doing once
after_s passes and then every step (papf report's progress, piped)."""

from __future__ import annotations

import threading
import time

from papf.console.progress import StepProgress


def test_a_job_done_in_time_prints_nothing():
    lines: list[str] = []
    with StepProgress("report", 3, enabled=None, out=lines.append, after_s=5.0) as p:
        for k in range(3):
            p.doing(f"reading r{k}.mcap")
            p.step(f"read r{k}.mcap")
    assert lines == []


def test_a_slow_job_shows_what_it_does_then_each_step():
    lines: list[str] = []
    shown = threading.Event()

    def out(line: str) -> None:
        lines.append(line)
        shown.set()

    with StepProgress("report", 4, enabled=None, out=out, after_s=0.05) as p:
        p.doing("reading a.mcap")
        p.step("read a.mcap")             # before after_s: silent
        p.doing("reading big.mcap")
        assert shown.wait(10.0)            # after_s passed while big.mcap is read
        p.step("read big.mcap")
        p.total = 5                        # a total learnt on the way
        p.step("drew charge.png")
    assert lines == ["report: 1/4  reading big.mcap ...", "report: 2/4  read big.mcap",
                     "report: 3/5  drew charge.png"]
    time.sleep(0.1)
    assert len(lines) == 3                 # nothing after the job ended


def test_report_steps_count_files_and_figures(tmp_path):
    """build_report tells its progress of every file read and figure drawn, and sets the total."""
    from nodes.recorder.writer import RunWriter
    from papf.report.report import build_report
    from schemas.messages import Clock, Odometry, PlannerStatus, WheelStates

    rec = tmp_path / "a.mcap"
    with RunWriter(rec, {"world": "open", "planner": "apf", "seed": "0"}) as w:
        for k in range(100):
            t = k * 20_000_000
            w.write_message("rosbot/clock", Clock(stamp_ns=t))
            w.write_message("rosbot/odom", Odometry(stamp_ns=t, x=0.002 * k, y=0.0, yaw=0.0,
                                                    v=0.1, w=0.0))
            w.write_message("rosbot/wheels", WheelStates(stamp_ns=t, speed=(1.2,) * 4,
                                                         torque=(0.05,) * 4))
        w.write_message("rosbot/planner/status", PlannerStatus(stamp_ns=t, state="reached"))
    lines: list[str] = []
    with StepProgress("report", 1, enabled=None, out=lines.append) as p:
        build_report([rec], tmp_path / "out", progress=p)
    assert p.done == p.total == 6, lines    # 1 file, charge, 3 figures of its world, tables
    assert lines[0] == "report: 1/3  read a.mcap" and lines[-1].startswith("report: 6/6  wrote report.md")
