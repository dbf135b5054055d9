"""``papf bench suite`` (bench/bench_suite.py): its sums and its checks before the work."""

from __future__ import annotations

from papf.cli import main


def test_per_test_rows_are_summed_per_file_and_tier(tmp_path):
    from bench.bench_suite import per_file

    (tmp_path / "cpu.gw0.tsv").write_text(
        "1.5\t2.0\tunit\ttests/unit/test_a.py::test_x\n0.5\t1.0\tunit\ttests/unit/test_a.py::test_y\n")
    # one run of every tier: a slow test's tier is its marker's, whichever file it is in
    (tmp_path / "cpu.gw1.tsv").write_text("3.0\t1.0\te2e\ttests/e2e/test_b.py::test_z[1]\n"
                                          "9.0\t5.0\tslow\ttests/e2e/test_b.py::test_long\n")
    rows = {(r["tier"], r["file"]): r for r in per_file(tmp_path)}
    assert rows[("unit", "tests/unit/test_a.py")] == {
        "tier": "unit", "file": "tests/unit/test_a.py", "tests": 2, "cpu_s": 2.0, "wall_s": 3.0}
    assert rows[("e2e", "tests/e2e/test_b.py")]["cpu_s"] == 3.0
    assert rows[("slow", "tests/e2e/test_b.py")]["tests"] == 1
    assert rows[("unit", "(all)")]["tests"] == 2 and rows[("slow", "(all)")]["cpu_s"] == 9.0
    assert [(r["file"] == "(all)", r["cpu_s"]) for r in per_file(tmp_path)] == [
        (True, 9.0), (True, 3.0), (True, 2.0), (False, 9.0), (False, 3.0), (False, 2.0)]


def test_a_foreign_csv_or_a_wrong_commit_is_refused_before_the_clone(tmp_path, capsys):
    foreign = tmp_path / "mine.csv"
    foreign.write_text("a,b\n1,2\n")
    assert main(["bench", "suite", "--csv", str(foreign)]) == 2
    assert "is not this benchmark's CSV" in capsys.readouterr().err
    assert foreign.read_text() == "a,b\n1,2\n"
    assert main(["bench", "suite", "--commit", "no-such-commit"]) == 2
    assert "is not a commit" in capsys.readouterr().err


def test_the_plugin_charges_each_test_to_its_tier_slow_by_its_marker(tmp_path):
    import os
    import subprocess
    import sys
    from pathlib import Path

    repo = Path(__file__).resolve().parents[2]
    (tmp_path / "tests" / "e2e").mkdir(parents=True)
    (tmp_path / "tests" / "e2e" / "test_t.py").write_text(
        "import pytest\n\n"
        "@pytest.mark.slow\ndef test_long():\n    pass\n\n"
        "def test_short():\n    pass\n")
    (tmp_path / "pytest.ini").write_text("[pytest]\nmarkers =\n    slow: long\n")
    env = {**os.environ, "PYTHONPATH": str(repo), "PAPF_CPU_PER_TEST": str(tmp_path / "cpu")}
    env.pop("PYTEST_XDIST_WORKER", None)
    proc = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "bench.pytest_cpu",
                           "-p", "no:cacheprovider", "tests/e2e/test_t.py"],
                          cwd=tmp_path, env=env, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout[-2000:]
    rows = [line.split("\t") for line in (tmp_path / "cpu.main.tsv").read_text().splitlines()]
    assert [(r[2], r[3]) for r in rows] == [("slow", "tests/e2e/test_t.py::test_long"),
                                            ("e2e", "tests/e2e/test_t.py::test_short")]
    assert all(float(r[0]) >= 0 and float(r[1]) >= 0 for r in rows)
