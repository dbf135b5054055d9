"""The command line's parser (common/cliparse.py, papf.cli.build_parser): did-you-mean for options,
commands and choices of papf and every node; what argparse accepts still accepted; a
non-finite, huge or negative number a usage error."""

from __future__ import annotations

import subprocess
import sys

import pytest

from common.cliparse import ArgumentParser
from tests.support.cli import papf

NUMERIC_OPTIONS = [
    (["teleop"], o) for o in ("--max-v", "--max-w", "--step-v", "--step-w", "--rate")
] + [(["animate", "a.mcap", "a.gif"], o) for o in ("--fps", "--speed", "--dpi")] + [
    (["rosbot-emulator"], o) for o in ("--scan-beams", "--seed", "--rate", "--cmd-timeout",
                                       "--battery-voltage")
] + [(["topic", "list"], "--duration"), (["topic", "echo", "odom"], "--count"),
     (["topic", "echo", "odom"], "--timeout"), (["topic", "hz", "odom"], "--window"),
     (["topic", "hz", "odom"], "--duration"), (["topic", "pub", "cmd_vel"], "--times"),
     (["topic", "pub", "cmd_vel"], "--rate"), (["plan", "--world", "energy"], "--dt"),
     (["plan", "--world", "energy"], "--seed"), (["plan", "--world", "energy"], "--timeout"),
     (["goal", "1", "0"], "--tolerance"), (["goal", "1", "0"], "--timeout"),
     (["experiment", "crowd"], "--workers"), (["experiment", "crowd"], "--runs"),
     (["experiment", "crowd"], "--seed"), (["experiment", "crowd"], "--timeout"),
     (["experiment", "random"], "--n"), (["experiment", "energy"], "--runs"),
     (["experiment", "traffic"], "--seed"), (["run", "--world", "energy"], "--view"), (["launch", "sim"], "--view")]


@pytest.mark.parametrize("prefix,option", NUMERIC_OPTIONS)
@pytest.mark.parametrize("value", ["nan", "inf", "-inf", "1e308", "-1", "1e999"])
def test_a_non_finite_huge_or_negative_number_is_a_usage_error(prefix, option, value, capsys):
    from papf.cli import build_parser

    with pytest.raises(SystemExit) as exc:
        build_parser(prefix[0]).parse_args([*prefix, f"{option}={value}"])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and option in err and err.count("\n") == 1


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
