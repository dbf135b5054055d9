"""``papf experiment cases`` (papf/experiments/doc_cases.py): the small studies behind the planner
tables of docs/planners.md write one summary row per case and world."""

from __future__ import annotations


def test_cases_study_writes_a_summary_row_per_case_and_world(tmp_path, monkeypatch):
    import csv

    from papf.experiments import doc_cases

    monkeypatch.setitem(doc_cases.STUDIES, "tiny", [
        doc_cases.Case("apf", "apf", ("papf-test-4",)),
        doc_cases.Case("two", "papf", ("papf-test-4", "papf-test-4"), ("d_q=1.0",), group_by_world=False)])
    doc_cases.run_cases(tmp_path, ["tiny"])
    rows = list(csv.DictReader((tmp_path / "tiny.csv").open()))
    assert [(r["case"], r["world"], r["mode"]) for r in rows] == [
        ("apf", "papf-test-4", "offline"), ("two", "papf-test-4 papf-test-4", "offline")]
    assert rows[0]["reached"] == "0/1" and rows[0]["outcomes"] == "stagnated"   # APF fails Test IV
    assert rows[1]["reached"] == "2/2" and "-" not in rows[1]["duration_s"]       # deterministic: one value
    assert len(list(csv.DictReader((tmp_path / "cases-runs.csv").open()))) == 3
    assert doc_cases._span([1.0, float("nan"), 2.04], 1) == "1.0-2.0" and doc_cases._span([], 1) == ""
