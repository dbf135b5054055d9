"""`papf bench planner --scenes energy` names the planner it leaves out, and why."""

from bench.bench_planner import CASES, left_out


def test_iapf_left_out_of_the_energy_scene_is_said():
    lines = left_out([label for label, _n, _s in CASES], ["energy"])
    assert any(line.startswith("bench planner: iapf left out") and "--scenes road" in line
               for line in lines)
    assert left_out([label for label, _n, _s in CASES], ["energy", "road"]) == []
