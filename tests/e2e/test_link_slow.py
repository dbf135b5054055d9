"""The split on a slow link (issue 30, "Done when"): over 100 ms ± 50 ms one way and over
200 ms + 0-150 ms one way, a robot/laptop split run reaches its goal with no collision and
the robot is never commanded past its limits.

Kept apart from test_link_split.py: these are the cases the slow-link driving (commands
stamped with the pose they were computed for, followed on the robot while fresh) is built
for; before it, a run over them drives in fits and starts, its commands arriving late.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from common.robot import A_MAX_M_S2, V_MAX_M_S, W_MAX_RAD_S
from tests.support.e2e import leftovers as _leftovers
from tests.support.link import CORRIDOR, split_run
from tests.support.link import commands as _commands
from tests.support.worlds import write_world

BUNCH_NS = 1_000_000   # [ns] commands received closer together than this came in one bunch
LINKS = {"100ms-50": "delay=50,jitter=100",      # 50-150 ms: 100 ms ± 50 ms
         "200ms-0-150": "delay=200,jitter=150"}  # 200-350 ms


@pytest.mark.parametrize("name", sorted(LINKS))
def test_a_split_run_over_a_slow_link_reaches_its_goal_within_the_robots_limits(name, tmp_path):
    world = write_world(tmp_path / "corridor.toml", CORRIDOR)
    ns, trace = f"t30slow{name[:3]}", tmp_path / "commands.jsonl"
    code, result, err = split_run(world, ns, LINKS[name], "--planner", "papf", "--set",
                                  "v_max=0.5", "--robot-trace", str(trace))
    delays = result["link_emulator"]["directions"]["out"]["delay_ms"]
    print(f"\n{name}: {result['outcome']} in {result['duration_s']} s, laptop->robot delay "
          f"p50 {delays['p50']} ms p99 {delays['p99']} ms, robot side "
          f"{result['link_emulator']['robot_side']}")
    assert (code, result["outcome"]) == (0, "reached"), (result.get("reason"), err[-3000:])
    assert result["collisions"] == 0
    assert delays["p50"] > 40.0                       # the link was slow
    cmds = _commands(Path(trace))
    assert cmds and all(abs(c["v"]) <= V_MAX_M_S + 1e-9 and abs(c["w"]) <= W_MAX_RAD_S
                        + 1e-9 for c in cmds)
    # the driver ramps on its 50 Hz grid (A_MAX * 20 ms a tick) and speeds up by at most two
    # ticks' worth after a late tick (common/drive.py rule 5); the trace's receive times bunch
    # under load, so a speed-up is checked per command, with room for a late tick. Slowing
    # down may use the whole time since the driver's last tick (a stop is never delayed by a
    # stall): bounded by A_MAX over the receive times of two commands back, plus two ticks
    # (0.061 m/s after an 86 ms stall was seen under load). Commands the robot received in
    # one bunch (a busy machine delivering them late, together) carry no trace of when the
    # driver sent them: the time runs from the last one received before the bunch (three
    # received within 1.2 us, slowing by 0.044 m/s, failed the two-back bound once under load)
    for k in range(2, len(cmds)):
        a, b = cmds[k - 1], cmds[k]
        step = abs(b["v"] - a["v"])
        if abs(b["v"]) > abs(a["v"]) or b["v"] * a["v"] < 0:
            assert step <= A_MAX_M_S2 * 0.020 * 3 + 1e-9, (a, b)
            continue
        j = k - 2
        while j > 0 and a["t_ns"] - cmds[j]["t_ns"] < BUNCH_NS:
            j -= 1
        before = cmds[j]
        assert step <= A_MAX_M_S2 * ((b["t_ns"] - before["t_ns"]) * 1e-9 + 0.040) + 1e-9, \
            (before, a, b)
    assert not _leftovers(ns)

