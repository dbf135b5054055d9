"""``papf experiment traffic`` (papf/experiments/traffic.py): each finished run kept, resumed after an interrupt."""

from __future__ import annotations

import pytest


def test_traffic_keeps_each_finished_run_and_resumes_after_an_interrupt(tmp_path, monkeypatch):
    from papf.experiments import traffic

    calls = []

    def fake_stack(world, planner, seed, timeout_s, **kw):
        calls.append(planner)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return object()

    def fake_row(name, planner, objects, trial, mcap):
        return {"world": name, "planner": planner, "objects": objects, "seed": 0,
                "outcome": "reached", "duration_s": 1.0, "path_length_m": 1.0, "collisions": 0,
                "left_road": 0, "lane_changes": 0, "min_speed_mps": 0.1, "max_speed_mps": 0.2,
                "wall_time_s": 1.0, "reason": ""}

    monkeypatch.setattr(traffic, "run_stack", fake_stack)
    monkeypatch.setattr(traffic, "road_row", fake_row)
    cases = (("apf", "none"), ("papf", "none"), ("arapf", "none"))
    world = traffic.ROAD_WORLDS[0]
    with pytest.raises(KeyboardInterrupt):
        traffic.run_traffic(tmp_path, [world], cases, echo=lambda _l: None)
    calls.clear()
    monkeypatch.setattr(traffic, "run_stack", lambda *a, **k: calls.append(a[1]) or object())
    rows = traffic.run_traffic(tmp_path, [world], cases, echo=lambda _l: None)
    assert calls == ["papf", "arapf"] and [r["planner"] for r in rows] == ["apf", "papf", "arapf"]
