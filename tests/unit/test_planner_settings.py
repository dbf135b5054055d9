"""The planners' safety settings (nodes/planner/settings.py, registry.load_params / check_setting):
no value switches avoidance off — floors, the repulsion product, the attraction ratio's
ceiling — and a settings file, ``--set`` and the live path are one check. Property-based over the ranges."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from common.errors import ConfigError
from nodes.planner import settings as S
from nodes.planner.registry import PLANNERS, check_setting, load_params, make_planner, settings_of

SETTINGS = settings(max_examples=60, deadline=None)


FLOORS = {"d_o": S.D_O_MIN_M, "k_vo_l": S.K_VO_L_MIN, "q_o": -S.CHARGE_MIN, "q_v": -S.CHARGE_MIN}
PROBES = ["d_o=1e-9", "k_vo_l=1e-300", "q_o=-1e-300", "q_v=-1e-300", "d_o=0.2",
          "arapf.k_ro_l=1e-9", "wang.k_rep_l=1e-9", "wang.rho_0=1e-9"]


@SETTINGS
@given(k_vg=st.floats(0.01, 60.0), q_g=st.floats(0.01, 12.0), k_vo_l=st.floats(1.0, 60.0),
       q_o=st.floats(-5.0, -0.2))
def test_the_attraction_ratio_has_a_measured_ceiling(k_vg, q_g, k_vo_l, q_o):
    from common.errors import ConfigError
    from nodes.planner import settings as S
    from nodes.planner.registry import load_params

    sets = [f"k_vg={k_vg!r}", f"q_g={q_g!r}", f"k_vo_l={k_vo_l!r}", f"q_o={q_o!r}"]
    ok = (k_vg <= S.K_VG_MAX and q_g <= S.Q_G_MAX and k_vo_l * abs(q_o) >= S.REPULSION_MIN
          and k_vg * q_g / (k_vo_l * abs(q_o)) <= S.ATTRACTION_RATIO_MAX)
    if ok:
        apf, _ = load_params("papf", None, sets)
        assert S.attraction_ratio(apf) <= S.ATTRACTION_RATIO_MAX
    else:
        with pytest.raises(ConfigError):
            load_params("papf", None, sets)


@pytest.mark.parametrize("planner,sets,match", [
    ("papf", ["k_vg=1000"], "k_vg=1000: must be"), ("apf", ["q_g=50"], "q_g=50: must be"),
    ("papf", ["k_vg=50", "k_vo_l=2"], "the goal's pull may be at most 5"),
    ("wang", ["k_att=1000"], "k_att=1000: must be"),
    ("wang", ["k_att=20", "k_rep_l=5"], None), ("wang", ["k_att=20", "k_rep_l=4.9"], "k_rep_l"),
    ("wang", ["control_offset_m=0.5"], "control_offset_m=0.5: must be")])
def test_attraction_settings_measured_to_collide_are_refused(planner, sets, match):
    from common.errors import ConfigError
    from nodes.planner.registry import load_params

    if match is None:
        load_params(planner, None, sets)
        return
    with pytest.raises(ConfigError, match=match):
        load_params(planner, None, sets)


@pytest.mark.parametrize("setting", PROBES)
def test_the_issues_probes_are_refused(setting):
    name = setting.split("=")[0]
    planner = name.split(".")[0] if "." in name else "papf"
    with pytest.raises(ConfigError, match="must be"):
        load_params(planner, None, [setting])


@settings(max_examples=60, deadline=None)
@given(name=st.sampled_from(sorted(FLOORS)), frac=st.floats(0.0, 1.0, exclude_max=True))
def test_no_value_between_zero_and_the_floor_is_taken(name, frac):
    value = FLOORS[name] * frac
    with pytest.raises(ConfigError):
        load_params("papf", None, [f"{name}={value!r}"])


@settings(max_examples=80, deadline=None)
@given(k=st.floats(S.K_VO_L_MIN, 50.0), qv=st.floats(-5.0, -S.CHARGE_MIN),
       qo=st.floats(-5.0, -S.CHARGE_MIN))
def test_the_repulsion_product_has_its_own_floor(k, qv, qo):
    sets = [f"k_vo_l={k!r}", f"q_v={qv!r}", f"q_o={qo!r}"]
    pull = 5.0 * 1.0 / (k * abs(qo))   # the default k_vg q_g over k_vo_l |q_o| (q_v in both)
    if k * qv * qo >= S.REPULSION_MIN and pull <= S.ATTRACTION_RATIO_MAX:
        apf, _ = load_params("apf", None, sets)
        assert apf.k_vo_l * apf.q_v * apf.q_o >= S.REPULSION_MIN
    elif k * qv * qo < S.REPULSION_MIN:
        with pytest.raises(ConfigError, match=r"k_vo_l\*q_v\*q_o"):
            load_params("apf", None, sets)
    else:   # pushed hard enough, but pulled harder still (the attraction ratio's ceiling)
        with pytest.raises(ConfigError, match=r"k_vg\*q_g/\(k_vo_l\*\|q_o\|\)"):
            load_params("apf", None, sets)


def test_every_swept_safety_range_starts_at_its_measured_floor():
    from nodes.planner.arapf import settings as AR
    from nodes.planner.wang import settings as W

    measured = {"d_o": S.D_O_MIN_M, "k_vo_l": S.K_VO_L_MIN, "k_ro_l": AR.K_RO_L_MIN,
                "k_rep_l": W.K_REP_L_MIN, "rho_0": W.RHO_0_MIN_M}
    for table in (S.APF, AR.ARAPF, W.WANG):
        for name, floor in measured.items():
            if name in table:
                assert table[name].safety and table[name].lo == floor and not table[name].lo_open
    for name in ("q_v", "q_o"):
        assert S.APF[name].hi == -S.CHARGE_MIN and not S.APF[name].hi_open
    apf, algo = load_params("arapf")
    S.check_strength(apf)
    PLANNERS["arapf"].check_strength(apf, algo)   # AR-APF's own product, at the defaults


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
