"""Figures in README.md and docs/ come from committed CSVs (papf/doctools/tables.py)."""

from pathlib import Path

import pytest

from common.errors import ConfigError
from papf.doctools.tables import check, doc_files, main, render

DOC = """Intro

<!-- table data/t.csv | name = Planner | charge = charge [mAh] : .2f | where preset=default -->
<!-- /table -->

PAPF used <!-- v data/t.csv | charge : .2f | where name=papf,preset=default -->?<!-- /v --> mAh.
"""
CSV = "name,preset,charge\napf,default,35.4212\npapf,default,23.8311\npapf,paper,30.1\n"


def _write(tmp_path: Path) -> Path:
    (tmp_path / "data").mkdir()
    (tmp_path / "data" / "t.csv").write_text(CSV)
    f = tmp_path / "doc.md"
    f.write_text(render(DOC, tmp_path))
    return f


def test_render_fills_tables_and_values_from_the_csv(tmp_path):
    text = _write(tmp_path).read_text()
    assert "| Planner | charge [mAh] |\n|---|---|\n| apf | 35.42 |\n| papf | 23.83 |\n" in text
    assert "30.10" not in text
    assert "PAPF used <!-- v data/t.csv | charge : .2f | where name=papf,preset=default -->23.83<!-- /v --> mAh." in text


def test_a_table_keeps_the_first_n_matching_rows(tmp_path):
    (tmp_path / "data").mkdir()
    (tmp_path / "data" / "t.csv").write_text(CSV)
    text = render("<!-- table data/t.csv | name | charge | where name=papf | first 1 -->\n"
                  "<!-- /table -->", tmp_path)
    assert "| papf | 23.8311 |" in text and "30.1" not in text
    assert "| apf |" in render("<!-- table data/t.csv | name | first 2 -->\n<!-- /table -->",
                               tmp_path)


def test_check_fails_when_a_number_in_the_prose_differs_from_its_csv(tmp_path):
    f = _write(tmp_path)
    assert check([f]) == []
    f.write_text(f.read_text().replace("-->23.83<", "-->23.87<"))
    diff = check([f])
    assert len(diff) == 1 and "-PAPF used" in diff[0] and "23.83" in diff[0]
    assert main(["check", str(f)]) == 1


def test_check_fails_when_the_csv_changes(tmp_path):
    f = _write(tmp_path)
    (tmp_path / "data" / "t.csv").write_text(CSV.replace("35.4212", "36.0"))
    assert check([f]) and main(["check", str(f)]) == 1


def test_a_value_must_match_exactly_one_row(tmp_path):
    (tmp_path / "data").mkdir()
    (tmp_path / "data" / "t.csv").write_text(CSV)
    with pytest.raises(ConfigError, match="one matching row"):
        render("<!-- v data/t.csv | charge | where name=papf -->x<!-- /v -->", tmp_path)


def test_the_repository_docs_match_their_csvs():
    assert check(doc_files()) == [], "run `make docs` (or fix the CSV) - see the diff above"
