"""`papf run` usage errors: a broken world file is one line and exit 2, before anything starts."""

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
    import subprocess
    import sys

    p = subprocess.run([sys.executable, "-m", "papf", "run", "--world", "open", "--dry-run",
                        "--set", "d_o=0.01"], capture_output=True, text=True, timeout=120)
    assert p.returncode == 2 and p.stdout == "" and "d_o" in p.stderr
    assert len(p.stderr.strip().splitlines()) == 1
