"""papf bench fleet's options and its in-process driver split (bench/bench_fleet.py,
bench/fleet_driver.py); the runs through the stack are the benchmark itself."""

import pytest

from bench.bench_fleet import fleet_world, parse
from bench.fleet_driver import split


@pytest.mark.parametrize("argv", [["--robots", "33"], ["--passing", "sideways"],
                                  ["--worlds", "fleet-swap", "--passing", "orca,maybe"],
                                  ["--worlds", "no-such-world"], ["--csv", "x.csv"]])
def test_bad_options_are_one_line_usage_errors(argv, capsys):
    with pytest.raises(SystemExit) as exc:
        parse(argv)
    assert exc.value.code == 2


def test_worlds_mode_compares_both_passing_modes_by_default():
    args = parse(["--worlds", "fleet-swap,fleet-ring-8"])
    assert args.passing == "off,orca" and args.timeout == 120.0


def test_driver_split_parts_add_up(tmp_path):
    """The driver's CPU of two robots split by part: every part measured, none more than the
    whole, physics (Bullet's steps) the largest."""
    row = split(fleet_world(tmp_path, 2, 0), 0.5, warm_s=0.1)
    parts = [row[k] for k in ("physics_ms", "tyres_ms", "contacts_ms", "gate_ms", "messages_ms")]
    assert row["robots"] == 2 and all(p > 0 for p in parts)
    assert sum(parts) == pytest.approx(row["cpu_ms_per_robot_cycle"], rel=0.01, abs=0.002)
    assert row["physics_ms"] == max(parts)
