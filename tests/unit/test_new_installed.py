"""``papf new planner`` in a non-editable install (site-packages) refuses in one line, exit 2,
saying why and what to do, and writes nothing; a checkout passes the same check."""

from pathlib import Path

import pytest

import nodes.planner.scaffold as scaffold
from common.errors import ConfigError
from papf.cli import main
from papf.cli.new import check_checkout


def _files(root: Path) -> set[str]:
    return {str(p.relative_to(root)) for p in root.rglob("*")}


def test_installed_copy_is_refused_with_exit_2_and_nothing_written(tmp_path, monkeypatch, capsys):
    site = tmp_path / "lib" / "python3.12" / "site-packages"
    (site / "nodes" / "planner").mkdir(parents=True)
    (site / "papf").mkdir()
    before = _files(tmp_path)
    monkeypatch.setattr(scaffold, "repo_root", lambda: site)

    assert main(["new", "planner", "mine", "--from", "apf"]) == 2

    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "installed copy" in err and "source tree" in err and "pip install -e ." in err
    assert _files(tmp_path) == before


def test_a_folder_without_pyproject_is_not_a_checkout(tmp_path):
    (tmp_path / "nodes" / "planner").mkdir(parents=True)
    with pytest.raises(ConfigError, match="pip install -e"):
        check_checkout(tmp_path)
    (tmp_path / "pyproject.toml").write_text("[project]\nname = 'papf-stack'\n")
    check_checkout(tmp_path)                     # a checkout: no error


def test_this_checkout_passes():
    check_checkout(scaffold.repo_root())
