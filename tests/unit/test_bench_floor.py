"""`papf bench sim --floor`: the lockstep chain in one process, on any packaged world."""

import pytest

from bench.sim_floor import CHAIN, chain


@pytest.mark.parametrize("world", ["energy", "crowd-standing"])
def test_the_floor_runs_the_chain_on_a_world_with_and_without_people(world):
    """A world with people also puts ``sim/people`` and ``sim/bodies``: the floor takes each
    message by its topic (it took odometry and wheels by their place once, and a world with
    people ended it in a traceback) and places the people where its LiDAR sees them."""
    res = chain(world, "apf", seed=1, timeout_s=2.0)
    assert res["outcome"] == "timeout" and res["sim_s"] == pytest.approx(2.0, abs=0.1)
    assert res["cycles"] == 20 and set(CHAIN) <= set(res["us_per_cycle"])
    assert all(v > 0 for v in res["us_per_cycle"].values())


def test_the_floor_refuses_a_fleet_in_one_line(capsys):
    """The chain is one robot's: a fleet's world is exit 2 and one line naming the bench that
    measures fleets (it was a KeyError's traceback)."""
    from papf.cli import main

    assert main(["bench", "sim", "--floor", "--world", "fleet-ring-8"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["papf bench sim: --floor runs one robot; 'fleet-ring-8' has 8 "
                   "(papf bench fleet measures a fleet)"]
