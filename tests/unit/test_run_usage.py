"""`papf run` usage errors: a broken world file is one line and exit 2, before anything starts."""

import socket

import pytest

from tests.support.cli import papf
from tests.support.e2e import papf_run


def test_broken_world_file_is_a_clear_usage_error(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[goal]\nposition = [1]\n")
    code, res, err = papf_run("--world", str(bad))
    assert code == 2 and res is None
    assert "goal.position" in err


def test_each_command_is_registered_by_the_module_the_cli_imports_for_it():
    """``papf COMMAND`` imports one module (papf.cli.COMMANDS): it must register exactly
    that command, and a full parse must know every command."""
    import argparse
    import importlib

    from papf.cli import COMMANDS, build_parser

    for name, module in COMMANDS:
        sub = argparse.ArgumentParser().add_subparsers()
        importlib.import_module(f"papf.cli.{module}").register(sub)
        assert list(sub.choices) == [name]
        assert list(build_parser(name)._subparsers._group_actions[0].choices) == [name]
    every = build_parser()._subparsers._group_actions[0].choices
    assert list(every) == [name for name, _ in COMMANDS]


def test_a_dry_run_is_preflighted_like_the_run():
    """Issue 31: `--dry-run` never prints a process list the run itself would refuse."""

    p = papf("run", "--world", "open", "--dry-run", "--set", "d_o=0.01", timeout=120)
    assert p.returncode == 2 and p.stdout == "" and "d_o" in p.stderr
    assert len(p.stderr.strip().splitlines()) == 1


def test_the_run_summary_shows_a_reason_as_text_no_markup_no_escapes(capsys):
    from types import SimpleNamespace

    from papf.cli.run import print_summary

    result = SimpleNamespace(outcome="failed", world="energy", planner="apf", seed=0,
                             duration_s=1.0, path_length_m=1.0, charge_mAh=1.0, energy_J=1.0,
                             collisions=0, sim_time_s=1.0, wall_time_s=1.0, fleet=(),
                             min_separation_m=None, faults=(),
                             reason="planner: \x1b]0;owned\x07[link=http://e]click[/link]")
    print_summary(result, "motor")
    out = capsys.readouterr().out
    assert "\x1b" not in out and "[link=http://e]click" in out
    assert "1.00 mAh (motor model)" in out          # the charge names the meter's model
    assert "faults" not in out and "lockstep" not in out


def test_the_run_summary_says_a_broken_lockstep_and_what_to_do(capsys):
    from types import SimpleNamespace

    from papf.cli.run import print_summary

    faults = ("base_driver at 3.40 s: no cmd_vel with stamp_ns=3400000000 within 2 s (wall); "
              "free running in real time until a command answers the latest scan",
              "base_driver at 9.10 s: no cmd_vel with stamp_ns=9100000000 within 2 s (wall); …")
    result = SimpleNamespace(outcome="reached", world="energy", planner="apf", seed=0,
                             duration_s=1.0, path_length_m=1.0, charge_mAh=1.0, energy_J=1.0,
                             collisions=0, sim_time_s=1.0, wall_time_s=1.0, fleet=(),
                             min_separation_m=None, faults=faults, reason="")
    print_summary(result)
    out = " ".join(capsys.readouterr().out.split())   # the table wraps its cells
    assert "base_driver at 3.40 s: no cmd_vel" in out and "and 1 more" in out
    assert "not bit-reproducible" in out and "--lockstep-timeout S" in out


@pytest.mark.parametrize("args,says", [
    (["--planner", "papff"], "did you mean 'papf'"),
    (["--planner", "PAPF"], "did you mean 'papf'"),
    (["--set", "unknown=1"], "unknown apf setting 'unknown'"),
    (["--set", "vmax=0.3"], "did you mean 'v_max'"),
    (["--set", "d_o=nan"], "d_o=nan: must be a finite number in [0.25, 25] m"),
    (["--seed", "-1"], "--seed=-1: must be an integer in [0, 4294967295]"),
    (["--params", "/bin/ls"], "is not a readable TOML file"),
    (["--params", "/nonexistent.toml"], "no such file"),
    (["--record", "/nonexistent/x.mcap"], "does not exist"),
    (["--timeout", "nan"], "--timeout=nan: must be a finite number"),
    (["--odom-hz", "nan"], "--odom-hz=nan: must be a finite number in (0, 1000] Hz"),
    (["--odom-hz", "30"], "use a rate that divides 1e9 ns"),
    (["--odom-hz", "20"], "must be a positive multiple of the 4000000 ns physics step"),
    (["--link", "lan", "--odom-hz", "10"], "with --link the robot side is the ROSbot's emulator"),
    (["--lockstep-timeout", "nan"], "--lockstep-timeout=nan: must be a finite number in (0, 60] s"),
    (["--lockstep-timeout", "0"], "--lockstep-timeout=0"),
    (["--realtime", "--lockstep-timeout", "5"], "with --realtime the simulator goes at the wall"),
    (["--link", "lan", "--lockstep-timeout", "5"], "never waits for a command: drop --lockstep"),
    (["--timeout", "inf"], "--timeout=inf"), (["--timeout", "0"], "--timeout=0"),
    (["--timeout", "-5"], "--timeout=-5"),
    (["--port", "-1"], "--port=-1: must be an integer in [1, 65535]"),
    (["--port", "70000"], "--port=70000"),
    (["--namespace", ""], "namespace"), (["--namespace", "*"], "namespace"),
    (["--namespace", "a//b"], "namespace"),
])
def test_bad_run_arguments_are_refused_before_anything_starts(args, says):
    p = papf("run", "--world", "open", "--json", *args)
    assert p.returncode == 2, (args, p.stdout, p.stderr)
    assert p.stdout == "" and says in p.stderr, (args, p.stderr)
    assert len(p.stderr.strip().splitlines()) == 1 and "Traceback" not in p.stderr


def test_a_port_held_by_another_listener_is_refused():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        port = s.getsockname()[1]
        p = papf("run", "--world", "open", "--port", port)
    assert p.returncode == 2 and "already listens" in p.stderr and p.stdout == ""


def test_a_namespace_another_launch_holds_is_a_usage_error_not_a_traceback(tmp_path, monkeypatch):
    """A real-time run publishes its key for `papf goal` (common.runauth): in a namespace a
    live launch of this user holds, exit 2 and one line that says what to do, before the
    router opens (a traceback with exit 1 until 2026-12-07)."""
    import os

    from common import runauth

    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    path = runauth.key_file("rosbot")
    path.parent.mkdir(mode=0o700)
    path.write_text(f"{'ab' * 16} {os.getpid()}\n")   # this test's process: alive
    p = papf("run", "--world", "open", "--realtime", "--timeout", "1", "--json")
    assert p.returncode == 2 and p.stdout == "", (p.returncode, p.stderr)
    assert "in use by another launch" in p.stderr and "--namespace" in p.stderr
    assert len(p.stderr.strip().splitlines()) == 1 and "Traceback" not in p.stderr


def test_plan_refuses_a_negative_seed_and_a_3d_world_is_refused_by_run():
    p = papf("plan", "--world", "open", "--seed", "-1")
    assert p.returncode == 2 and "--seed=-1" in p.stderr and "Traceback" not in p.stderr
    p = papf("run", "--world", "wang-3d-fig9", "--json")
    assert p.returncode == 2 and "is 3-D" in p.stderr and p.stdout == ""


def test_a_longer_lockstep_timeout_reaches_the_simulator_and_the_pairing_nodes():
    """The planner's and tracker's pair timeout stays a second past the simulator's wait, so a
    loaded machine never changes an answer (common.units.pair_timeout_s)."""
    from papf.launch.run import RunConfig, resolve_run

    def argv(cfg, name):
        return list(resolve_run(cfg).nodes[name])

    default = RunConfig(world="open", objects="tracker")
    world = argv(default, "base_driver")
    assert world[world.index("--lockstep-timeout") + 1] == "2"
    assert "--pair-timeout" not in argv(default, "planner") + argv(default, "tracker")
    longer = RunConfig(world="open", objects="tracker", lockstep_timeout_s=10.0)
    world = argv(longer, "base_driver")
    assert world[world.index("--lockstep-timeout") + 1] == "10"
    for name in ("planner", "tracker"):
        args = argv(longer, name)
        assert args[args.index("--pair-timeout") + 1] == "11", name


def test_the_launcher_calls_a_run_stuck_only_after_the_simulators_whole_wait():
    from papf.launch.run import RunConfig, stall_s
    from papf.launch.sequence import STALL_S

    assert stall_s(RunConfig(world="open")) == STALL_S == 20.0
    assert stall_s(RunConfig(world="open", lockstep_timeout_s=10.0)) == STALL_S
    assert stall_s(RunConfig(world="open", lockstep_timeout_s=30.0)) == 60.0
