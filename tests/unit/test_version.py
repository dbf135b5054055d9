"""One version from one place: ``papf --version``, the package metadata, a recording."""

from __future__ import annotations

import importlib.metadata

import pytest
from mcap.reader import make_reader

import common
import papf
from nodes.recorder.writer import RUN_METADATA, RunWriter
from papf.cli import main


def test_cli_version_is_the_package_metadata(capsys):
    with pytest.raises(SystemExit) as stop:
        main(["--version"])
    assert stop.value.code == 0
    installed = importlib.metadata.version("papf-stack")
    assert capsys.readouterr().out.strip() == f"papf-stack {installed}"
    assert installed == common.__version__ == papf.__version__


def test_new_recording_states_the_same_version(tmp_path):
    path = tmp_path / "run.mcap"
    with RunWriter(path, {"world": "energy"}):
        pass
    with open(path, "rb") as f:
        reader = make_reader(f)
        header = reader.get_header()
        meta = {m.name: m.metadata for m in reader.iter_metadata()}[RUN_METADATA]
    assert header.library == f"papf-stack/{common.__version__}"
    assert meta["software_version"] == importlib.metadata.version("papf-stack")
