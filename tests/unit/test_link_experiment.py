"""`papf experiment link`: its runs, its rows, its table and picture (no run made here)."""

from __future__ import annotations

import argparse

import pytest

from common.errors import ConfigError
from papf.cli.experiment_link import todo_of
from papf.experiments.link import (
    LINKS,
    PLANNERS,
    SWEEP_MS,
    Case,
    charge_vs_lan,
    markdown,
    reached_up_to,
    row_of,
    write_outputs,
)
from papf.launch.outcome import RunResult
from papf.link.spec import parse_spec


def _args(**kw) -> argparse.Namespace:
    base = {"planners": "apf,papf", "links": ",".join(label for label, _ in LINKS),
            "outage": "10@20", "sweep": ",".join(map(str, SWEEP_MS))}
    return argparse.Namespace(**{**base, **kw})


def test_the_default_runs_are_planners_x_links_x_outages_and_the_sweep():
    todo = todo_of(_args())
    profiles = [c for c in todo if c.study == "profiles"]
    assert len(profiles) == len(PLANNERS) * len(LINKS) * 2
    assert len([c for c in todo if c.study == "sweep"]) == len(PLANNERS) * len(SWEEP_MS)
    for c in todo:      # every spec is one papf run --link takes
        parse_spec(c.spec)
    issue = next(c for c in profiles if c.link == "200+0-150ms" and c.outage != "none")
    spec = parse_spec(issue.spec)
    assert (spec.delay_ms, spec.jitter_max_ms, spec.outages) == (200.0, 150.0, ((10.0, 20.0),))


def test_options_narrow_the_runs_and_mistakes_are_refused():
    todo = todo_of(_args(planners="papf", links="lte", outage="none", sweep="none"))
    assert [(c.planner, c.link, c.outage) for c in todo] == [("papf", "lte", "none")]
    for kw, says in (({"links": "wfi"}, "valid names"), ({"sweep": "1,x"}, "whole milli"),
                     ({"outage": "10"}, "LENGTH@START"), ({"planners": "nope"}, "valid names"),
                     ({"sweep": "-5"}, "[0, 60000]")):
        with pytest.raises(ConfigError, match=None) as err:
            todo_of(_args(**kw))
        assert says in str(err.value)


def _result(outcome: str, charge: float, late: int | None = 3) -> RunResult:
    stats = {"outage_s": 10.0, "robot_side": {"watchdog_stops": 2, "late_commands": late},
             "directions": {"out": {"delay_ms": {"p50": 210.0, "p99": 340.0}},
                            "back": {"delay_ms": {"p50": 220.0, "p99": 345.0}}}}
    result = RunResult(outcome, "apf", "energy", 0, 100.0, 10.0, charge, 1.0, 0, 100.0, 120.0,
                       reason="why", link_emulator=stats)
    result.link = {"rtt_p50_ms": 450.0, "rtt_p99_ms": 700.0, "commands": 900,
                   "late_commands": 4, "stale_commands": 1}   # the robot side's count
    return result


def test_a_row_holds_the_run_and_what_the_link_did():
    row = row_of(Case("profiles", "apf", "wifi", "wifi,outage=10@20", "10s@20s"),
                 _result("reached", 30.0))
    assert row["charge_mAh"] == 30.0 and row["delay_out_p50_ms"] == 210.0
    assert (row["outage_s"], row["watchdog_stops"], row["late_commands"]) == (10.0, 2, 3)
    assert (row["rtt_p50_ms"], row["refused_commands"], row["commands"]) == (450.0, 5, 900)


def _rows():
    out = []
    for planner, base in (("apf", 30.0), ("papf", 20.0)):
        for link, k in (("lan", 1.0), ("wifi", 1.1), ("lte", 1.5)):
            out.append(row_of(Case("profiles", planner, link, link), _result("reached", base * k)))
        for ms, outcome in ((0, "reached"), (100, "reached"), (300, "stagnated"), (500, "reached")):
            out.append(row_of(Case("sweep", planner, f"{ms}ms", f"delay={ms}"),
                              _result(outcome, base)))
    return out


def test_charge_against_lan_and_the_delay_each_planner_reaches_up_to():
    rows = _rows()
    profiles = [r for r in rows if r["study"] == "profiles"]
    vs = charge_vs_lan(profiles)
    assert [vs[i] for i, r in enumerate(profiles) if r["planner"] == "apf"] == [0.0, 10.0, 50.0]
    # the first failure ends the range: a success at 500 ms after a failure at 300 is luck
    assert reached_up_to([r for r in rows if r["study"] == "sweep"]) == {"apf": "100ms",
                                                                       "papf": "100ms"}
    text = markdown(profiles, [r for r in rows if r["study"] == "sweep"])
    assert "| apf | lte | none | reached |" in text and "Reaches its goal up to: apf 100ms" in text
    assert "| 450.0 | 5 / 900 |" in text


def test_the_outputs_are_written(tmp_path):
    write_outputs(tmp_path, _rows())
    assert {p.name for p in tmp_path.iterdir()} == {"link.csv", "link-sweep.csv", "link.md",
                                                    "link.png"}
    assert (tmp_path / "link.png").read_bytes()[:4] == b"\x89PNG"
    assert "charge_vs_lan_pct" in (tmp_path / "link.csv").read_text().splitlines()[0]
