"""Issue "trust no input", items 1 and 2: parameters cannot switch safety off; extreme
and backwards stamps are dropped and counted like bad payloads."""

from __future__ import annotations

import logging
import subprocess
import sys

import pytest

from common.errors import ConfigError
from common.transport import Node
from common.units import MAX_STAMP_NS, StampGuard
from nodes.base_driver.core import DriverConfig
from nodes.energy_meter.core import EnergyMeter
from nodes.planner.loop import PlannerLoop
from nodes.planner.registry import check_setting, load_params, make_planner, settings_of
from schemas import Keys
from schemas.keys import STAMP_ORDERED
from schemas.messages import Goal
from tests.support.messages import odom as _odom
from tests.support.messages import scan_63 as _scan


@pytest.mark.parametrize("setting", ["d_o=nan", "d_o=-1", "d_o=0", "v_max=0", "v_max=inf",
                                     "v_max=5", "k_vo_l=0", "q_o=1", "w_max=nan"])
def test_parameter_cannot_switch_obstacle_avoidance_off(setting):
    name = setting.split("=")[0]
    with pytest.raises(ConfigError, match=rf"^{name}=\S+: must be a finite number in "):
        make_planner("papf", None, [setting])


def test_params_file_is_checked_like_set(tmp_path):
    f = tmp_path / "p.toml"
    f.write_text("d_o = nan\n")
    with pytest.raises(ConfigError, match=r"d_o=nan: must be a finite number in \[0.25, 25\] m"):
        load_params("apf", f)
    f.write_text("[wang]\nrho_0 = -1.0\n")
    with pytest.raises(ConfigError, match="rho_0=-1.0"):
        load_params("wang", f)


def test_live_parameter_path_is_the_same_check():
    assert check_setting("papf", "d_o", 0.7) == ("apf", 0.7)
    assert check_setting("papf", "max_quarks", "4") == ("papf", 4)
    with pytest.raises(ConfigError, match="did you mean 'v_max'"):
        check_setting("papf", "vmax", 0.3)
    table, spec, default = settings_of("arapf")["passage_width"]
    assert (table, spec.choices, default) == ("arapf", ("opening", "gap"), "opening")


def test_nodes_check_their_settings_again():
    with pytest.raises(ConfigError, match="watchdog"):
        DriverConfig.from_rates(watchdog_s=float("inf"))
    with pytest.raises(ConfigError, match="stale_timeout"):
        PlannerLoop(make_planner("apf"), stale_timeout_s=float("nan"))
    with pytest.raises(ConfigError, match="initial_soc"):
        EnergyMeter("motor", {"initial_soc": "2"})


def test_node_options_refused_at_parse_time_with_exit_2():
    for argv in (["nodes.base_driver", "--watchdog", "0"],
                 ["nodes.lidar_sim", "--beams", "nan"],
                 ["nodes.planner", "--stale-timeout", "inf"],
                 ["nodes.planner", "--set", "d_o=nan"]):
        p = subprocess.run([sys.executable, "-m", *argv], capture_output=True, text=True,
                           timeout=60)
        assert p.returncode == 2, (argv, p.stderr)
        assert "must be" in p.stderr


# -- item 2: stamps ------------------------------------------------------------------------------
@pytest.mark.parametrize("stamp", [-2**63, -1, MAX_STAMP_NS + 1, 2**64 - 1])
def test_extreme_stamp_is_dropped_and_counted(stamp):
    node = Node("probe", None, Keys("t"), logging.getLogger("probe"))
    assert node.accept("odom", _odom(stamp).to_bytes()) is None
    assert node.accept("scan", _scan(stamp).to_bytes()) is None
    assert node.bad_messages == {"odom": 1, "scan": 1}


def test_backwards_stamp_is_dropped_on_ordered_topics_only():
    g = StampGuard(STAMP_ORDERED)
    assert [g.check("odom", _odom(t)) == "" for t in (100, 200, 150, 200, 300)] == [
        True, True, False, True, True]
    assert g.check("odom", _odom(0)) == ""            # a new run restarts sim time at 0
    assert g.check("odom", _odom(20)) == ""
    assert g.check("goal", Goal(stamp_ns=5, x=0, y=0)) == ""
    assert g.check("goal", Goal(stamp_ns=1, x=0, y=0)) == ""   # not an ordered topic


def test_planner_ignores_an_extreme_stamp_pair():
    """The reproduction: odom + scan at 2**64-1 made the planner stagnate at once."""
    node = Node("planner", None, Keys("t"), logging.getLogger("p"))
    loop = PlannerLoop(make_planner("apf"))
    out = loop.on_message("goal", Goal(stamp_ns=0, x=5.0, y=0.0), 0.0)
    for t in (0, 100_000_000):
        for topic, msg in (("odom", _odom(t)), ("scan", _scan(t))):
            out += loop.on_message(topic, node.accept(topic, msg.to_bytes()), 0.0)
    for stamp in (2**64 - 1, -2**63):
        for topic, msg in (("odom", _odom(stamp)), ("scan", _scan(stamp))):
            got = node.accept(topic, msg.to_bytes())
            assert got is None
    statuses = [m.state for t, m in out if t == "planner/status"]
    assert statuses == ["ready", "driving", "driving"]
    assert sum(node.bad_messages.values()) == 4


def test_planner_state_neither_built_nor_returned_when_nobody_listens():
    """want_state false: the same commands and statuses, no planner/state (debug) at all."""
    def run(want: bool) -> list:
        loop = PlannerLoop(make_planner("apf"), want_state=lambda: want)
        out = loop.on_message("goal", Goal(stamp_ns=0, x=5.0, y=0.0), 0.0)
        for t in (0, 100_000_000, 200_000_000):
            out += loop.on_message("odom", _odom(t), 0.0) + loop.on_message("scan", _scan(t), 0.0)
        out += loop.on_message("scan", _scan(900_000_000), 0.0) + loop.poll(10.0)  # stale
        out += loop.on_message("goal", Goal(stamp_ns=0, x=0.05, y=0.0), 0.0)  # within reach
        t = 1_000_000_000
        return out + loop.on_message("odom", _odom(t), 0.0) + loop.on_message("scan", _scan(t), 0.0)

    full, lean = run(True), run(False)
    assert [t for t, _ in full].count("planner/state") == 5
    assert [m.state for t, m in lean if t == "planner/status"][-1] == "reached"
    assert any(m.mode == "stale" for t, m in full if t == "planner/state")
    assert [(t, m) for t, m in full if t != "planner/state"] == lean
