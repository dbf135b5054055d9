"""Issue #35, the rough edges a new user hit: each line typed as the issue writes it, then
what a user expects of it."""

from __future__ import annotations

import io
import subprocess
import sys

import pytest

from common.cliparse import ArgumentParser
from common.text import error_text
from tests.support.cli import papf


# -- did-you-mean for flags, commands and world names ---------------------------------------
def test_a_misspelt_required_flag_is_named_with_the_flag_meant():
    res = papf("run", "--wrld", "energy")
    assert res.returncode == 2 and res.stdout == ""
    assert res.stderr.strip() == ("papf run: unrecognized option --wrld; did you mean --world? "
                                  "(see papf run --help)")


def test_a_misspelt_command_and_subcommand_get_a_did_you_mean():
    res = papf("rnu")
    assert res.returncode == 2 and "did you mean run?" in res.stderr
    res = papf("topic", "eco", "scan")
    assert res.returncode == 2 and "did you mean echo?" in res.stderr


def test_a_misspelt_world_name_names_the_world_meant():
    res = papf("run", "--world", "enrgy")
    assert res.returncode == 2
    assert "no packaged world named 'enrgy'; did you mean 'energy'?" in res.stderr


@pytest.mark.parametrize("node,typo,meant", [("planner", "--planer", "--planner"),
                                             ("base_driver", "--drivr", "--driver"),
                                             ("lidar_sim", "--wrld", "--world"),
                                             ("energy_meter", "--modl", "--model"),
                                             ("recorder", "--otu", "--out")])
def test_every_node_suggests_its_own_options(node, typo, meant):
    res = subprocess.run([sys.executable, "-m", f"nodes.{node}", typo, "x"], capture_output=True,
                         text=True, timeout=60, stdin=subprocess.DEVNULL)
    assert res.returncode == 2
    assert f"unrecognized option {typo}; did you mean {meant}" in res.stderr
    assert res.stderr.count("\n") == 1   # one line, no usage block


def _parser() -> ArgumentParser:
    p = ArgumentParser(prog="t")
    p.add_argument("--world", required=True)
    p.add_argument("--count", "-n", type=int)
    p.add_argument("--verbose", "-v", action="store_true")
    p.add_argument("--start")
    p.add_argument("rest", nargs="*")
    return p


@pytest.mark.parametrize("argv", [["--world", "w"], ["--wor", "w"], ["--world=w", "-n5", "-v"],
                                  ["--world", "w", "--start=-1,2"], ["--world", "w", "-n", "-3"],
                                  ["--world", "w", "--", "--anything"], ["--world", "w", "a", "-1"]])
def test_what_argparse_accepts_is_still_accepted(argv):
    assert _parser().parse_args(argv).world == "w"


def test_an_unknown_option_is_found_before_the_missing_required_one(capsys):
    with pytest.raises(SystemExit) as exc:
        _parser().parse_args(["--wrld=w"])
    assert exc.value.code == 2
    assert "unrecognized option --wrld; did you mean --world?" in capsys.readouterr().err


def test_a_misspelt_choice_gets_the_nearest_choice(capsys):
    p = ArgumentParser(prog="t")
    p.add_argument("--mode", choices=("client", "peer", "router"))
    with pytest.raises(SystemExit):
        p.parse_args(["--mode", "clinet"])
    assert "invalid choice clinet; did you mean client?" in capsys.readouterr().err


# -- error lines whole, wrapped for a terminal --------------------------------------------
def test_a_long_error_line_is_whole_when_piped():
    res = papf("run", "--world", "papf-tst-1")
    assert res.returncode == 2 and "(or pass a path to a .toml file)" in res.stderr
    assert "chars)" not in res.stderr and res.stderr.count("\n") == 1


class _Tty(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_a_long_error_is_wrapped_at_words_for_a_terminal(monkeypatch):
    monkeypatch.setenv("COLUMNS", "60")
    message = "no packaged world named 'x'; packaged worlds: " + ", ".join(f"w{i}" for i in range(80))
    text = error_text("papf run", message, _Tty())
    lines = text.split("\n")
    assert len(lines) > 3 and all(len(line) <= 60 for line in lines)
    assert " ".join(line.strip() for line in lines) == f"papf run: {message}"
    assert error_text("papf run", message, io.StringIO()) == f"papf run: {message}"


# -- papf report: the output checked before the work; one HTML file ------------------------
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


# -- one --port / --port-range / PORT= story ------------------------------------------------
def _ports_of(dry_run_json: str) -> list[list[int]]:
    import json
    import re

    procs = json.loads(dry_run_json)["processes"]
    return [[int(p) for a in proc["argv"] for p in re.findall(r"^tcp/[^:]+:(\d+)$", a)]
            for proc in procs]


@pytest.mark.parametrize("command", [["run", "--world", "energy"],
                                     ["launch", "sim", "--world", "energy"]])
def test_port_range_keeps_the_router_and_every_node_inside_it(command):
    from papf.launch.supervisor import free_port

    lo = min(free_port(), 60000)
    res = papf(*command, "--port-range", f"{lo}-{lo + 40}", "--dry-run")
    assert res.returncode == 0, res.stderr
    ports = _ports_of(res.stdout)
    assert all(lo <= p <= lo + 40 for proc in ports for p in proc)
    router = ports[0][0]
    listening = [proc[-1] for proc in ports[1:]]   # each peer node's --listen
    assert len(set(listening)) == len(listening) and router not in listening
    assert all(proc[0] == router for proc in ports[1:])   # every node connects to the router


def test_port_range_errors_are_one_line_before_anything_starts():
    res = papf("run", "--world", "energy", "--port-range", "90-80", "--dry-run")
    assert res.returncode == 2 and "give LO-HI" in res.stderr
    res = papf("run", "--world", "energy", "--port", "7447", "--port-range", "9000-9010")
    assert res.returncode == 2 and "--port 7447 is outside --port-range 9000-9010" in res.stderr
    res = papf("experiment", "energy", "--port", "7600", "--workers", "2", "--out", "x")
    assert res.returncode == 2 and "give --port-range" in res.stderr


def test_launch_port_sets_the_routers_port_on_the_profiles_interface():
    res = papf("launch", "robot", "--port", "7600", "--dry-run")
    assert res.returncode == 0, res.stderr
    assert "tcp/0.0.0.0:7600" in res.stdout and "tcp/127.0.0.1:7600" in res.stdout
    res = papf("launch", "laptop", "--port", "7600", "--world", "energy")
    assert res.returncode == 2 and "runs no router" in res.stderr


def test_experiment_port_puts_every_runs_router_on_it(tmp_path, monkeypatch):
    from rich.console import Console

    from papf.experiments.energy import EnergyExperiment, run_experiment
    from papf.launch.portrange import PORT_ENV
    from tests.unit.test_experiment_energy import FakeRuns

    monkeypatch.setenv(PORT_ENV, "7600")
    fake = FakeRuns()
    run_experiment(EnergyExperiment(out=tmp_path, runs=2, planners=("apf",)),
                   Console(file=io.StringIO()), run_fn=fake)
    assert [c.port for c in fake.configs] == [7600, 7600]


def test_make_demo_takes_port_and_port_range():
    import shutil
    from pathlib import Path

    if shutil.which("make") is None:
        pytest.skip("no make")
    root = Path(__file__).resolve().parents[2]
    res = subprocess.run(["make", "-n", "-C", str(root), "demo", "PORT=7600",
                          "PORT_RANGE=7600-7620", "VENV=.venv"], capture_output=True, text=True,
                         timeout=60)
    assert "papf run --world energy --planner papf --port 7600 --port-range 7600-7620" in res.stdout


# -- tables that fit the terminal ------------------------------------------------------------
def _wide_table():
    from rich.table import Table

    t = Table(title="robots")
    for col in ("robot", "planner", "outcome", "time s", "path m", "mAh", "coll.", "sep. m",
                "disc. s", "reason"):
        t.add_column(col)
    t.add_row("r1", "wang-apf", "stagnated", "49.18", "4.91", "11.79", "0", "0.552", "0.00",
              "no progress for 20 s within 1.5 m of the goal")
    return t


def test_a_piped_table_is_one_line_a_row_never_wrapped_or_cut(monkeypatch):
    from rich.console import Console

    from papf.console.tables import print_table

    monkeypatch.setenv("COLUMNS", "80")
    out = io.StringIO()
    print_table(_wide_table(), Console(file=out))
    lines = out.getvalue().splitlines()
    row = next(line for line in lines if "r1" in line)
    assert "no progress for 20 s within 1.5 m of the goal" in row and "wang-apf" in row
    assert "…" not in out.getvalue() and len(row) > 80
    assert "\x1b" not in out.getvalue()


def test_a_narrow_terminal_gets_whole_values_one_per_line():
    from rich.console import Console

    from papf.console.tables import print_table

    out = io.StringIO()
    print_table(_wide_table(), Console(file=out, force_terminal=True, width=80, color_system=None))
    text = out.getvalue()
    assert all(len(line) <= 80 for line in text.splitlines())
    assert "robot: r1" in text and "  planner: wang-apf" in text
    assert "  reason:  no progress for 20 s within 1.5 m of the goal" in text
    out = io.StringIO()   # a table that fits stays a table
    small = _wide_table()
    small.columns = small.columns[:3]
    print_table(small, Console(file=out, force_terminal=True, width=80, color_system=None))
    assert "┃ robot ┃ planner  ┃ outcome   ┃" in out.getvalue()


def test_the_reports_markdown_table_becomes_a_table_that_fits():
    from papf.console.tables import markdown_table

    t = markdown_table("| planner | charge [mAh, motor model] |\n|---|---|\n| pa\\|pf | 23.95 |\n")
    assert [c.header.plain for c in t.columns] == ["planner", "charge [mAh, motor model]"]
    assert [c._cells[0].plain for c in t.columns] == ["pa|pf", "23.95"]
    assert markdown_table("no table here") is None


# -- YAML and TOML errors with line and column ----------------------------------------------
def test_a_broken_world_file_names_line_and_column(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('[goal]\nposition = [1, 2]\nname = "x\n')
    res = papf("plan", "--world", str(bad))
    assert res.returncode == 2
    assert "is not valid TOML: line 3, column 10: Illegal character" in res.stderr
    assert "(in 'name = \"x')" in res.stderr
    bad.write_text("[goal]\nposition = [1, 2\n")
    res = papf("plan", "--world", str(bad))
    assert "line 2, at the end of the file: Unclosed array" in res.stderr


def test_a_broken_map_yaml_names_line_and_column(tmp_path):
    bad = tmp_path / "map.yaml"
    bad.write_text("image: x.pgm\nresolution: [0.05\norigin: [0, 0, 0]\n")
    res = papf("plan", "--world", str(bad), "--start", "0,0", "--goal", "1,1")
    assert res.returncode == 2
    assert ("is not valid YAML: line 3, column 7: expected ',' or ']', but got ':' (while "
            "parsing a flow sequence started at line 2, column 13)") in res.stderr


def test_a_broken_topic_pub_value_names_its_column():
    res = papf("topic", "pub", "cmd_vel", "{v: 0.1, w: 0.0", "--once")
    assert res.returncode == 2
    assert res.stderr.startswith("papf topic pub: VALUE '{v: 0.1, w: 0.0' is not YAML/JSON: "
                                 "column 16: expected ',' or '}'")


@pytest.mark.parametrize("kind", ["params", "profile"])
def test_broken_settings_and_profiles_name_line_and_column(tmp_path, kind):
    if kind == "params":
        f = tmp_path / "p.toml"
        f.write_text("v_max = 0.3\nd_o = \n")
        res = papf("plan", "--world", "energy", "--params", str(f))
    else:
        f = tmp_path / "prof.toml"
        f.write_text('name = "x"\nrouter = tru\n')
        res = papf("launch", str(f))
    assert res.returncode == 2 and "is not valid TOML: line 2, column" in res.stderr


# -- the fix hint of a bag whose topic names are not the ROSbot's ----------------------------
def test_a_bag_with_other_names_gets_the_exact_topics_option(tmp_path):
    from tests.support.bags import write_bag

    bag = tmp_path / "bag"
    write_bag(bag, names={"odom": "/wheel_odom"})   # neither the ROSbot's name nor the face's
    res = papf("report", str(bag))
    assert res.returncode == 2 and \
        res.stderr.strip().endswith("Read it with --topics odom=/wheel_odom")
    assert "chars)" not in res.stderr
    res = papf("report", str(bag), "--topics", "odom=/wheel_odom")
    assert res.returncode == 0, res.stderr
    res = papf("info", str(bag))   # info still lists what the bag holds
    assert res.returncode == 0 and "/wheel_odom" in res.stdout and \
        "--topics odom=/wheel_odom" in res.stderr


def test_a_benchmark_refuses_a_foreign_csv_before_measuring(tmp_path, capsys):
    """Issue #35, output checks before work: every command that writes files checks them
    first (papf bench planner takes seconds to minutes before it writes its CSV)."""
    from papf.cli import main

    mine = tmp_path / "mine.csv"
    mine.write_text("the user's own table\n")
    assert main(["bench", "planner", "--csv", str(mine), "--cycles", "10"]) == 2
    out, err = capsys.readouterr()
    assert "is not this benchmark's CSV" in err
    assert out == ""   # no case measured (each prints its JSON line as it ends)
    assert mine.read_text() == "the user's own table\n"
