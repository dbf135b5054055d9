"""``papf experiment safety-floor`` (papf/experiments/safety_floor.py): its sweep read into ceilings and
the tolerated attraction ratio, its CSV checked before a run, and the settings' ceilings
are the ones its committed CSV measured."""

from __future__ import annotations


def test_safety_floor_refuses_a_csv_that_is_not_its_table_before_a_run(tmp_path, capsys):
    from papf.cli import main

    f = tmp_path / "x.csv"
    f.write_text("not,ours\n")
    assert main(["experiment", "safety-floor", "--attraction", "--out", str(f)]) == 2
    assert "not this benchmark's CSV" in capsys.readouterr().err and f.read_text() == "not,ours\n"


def test_the_attraction_sweep_reads_ceilings_and_the_tolerated_ratio():
    from papf.experiments import safety_floor as sf

    def row(planner, param, value, outcome, ratio):
        return {"world": "w", "planner": planner, "param": param, "value": f"{value:g}",
                "outcome": outcome, "ratio": ratio}

    rows = [row("apf", "k_vg", 5, "reached", 0.5), row("apf", "k_vg", 10, "reached", 1.0),
            row("apf", "k_vg", 25, "collision", 2.5), row("apf", "k_vg", 50, "reached", 5.0),
            row("apf", "v_max", 0.9, "collision", 0.5),          # not a ratio row
            row("papf", "combo", 0, "reached", 2.0)]
    sweep = {"k_vg": (("apf",), (5.0, 10.0, 25.0, 50.0))}
    assert sf.floors_of(rows, sweep) == {"k_vg": 10.0}      # stops at the first collision
    assert sf.ratio_limit(rows, ("apf", "papf")) == 2.0      # below the smallest colliding ratio
    assert sf.attraction_ratio("papf", ("k_vo_l=2.0", "k_vg=5.0")) == 2.5
    assert sf.attraction_ratio("wang", ("k_att=20.0",)) == 4.0


def test_the_ceilings_are_the_measured_ones():
    import csv
    from pathlib import Path

    from nodes.planner import settings as S
    from nodes.planner.wang import settings as W
    from papf.experiments import safety_floor as sf

    path = Path(__file__).resolve().parents[2] / "docs" / "data" / "safety-attraction.csv"
    rows = list(csv.DictReader(path.open()))
    found = sf.floors_of(rows, sf.ATTRACTION_SWEEP)
    assert (found["k_vg"], found["q_g"], found["control_offset_m"]) == (
        S.K_VG_MAX, S.Q_G_MAX, W.CONTROL_OFFSET_MAX_M)
    wang_only = {"k_att": ((sf.WANG,), sf.ATTRACTION_SWEEP["k_att"][1])}   # wang-apf: below
    assert sf.floors_of(rows, wang_only)["k_att"] == W.K_ATT_MAX
    assert "k_att" not in found   # wang-apf, the paper's failing baseline, collides at Table 1's
    assert sf.ratio_limit(rows, (sf.APF_PAIR + (sf.ARAPF,))) == S.ATTRACTION_RATIO_MAX
    assert sf.ratio_limit(rows, (sf.WANG,)) == W.WANG_RATIO_MAX
