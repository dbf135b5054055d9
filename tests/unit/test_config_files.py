"""Settings files, launch profiles and a VALUE a user gives, read safely (nodes/planner/registry.py,
papf/launch/profile.py, worlds/maps.py, papf/bus/fields.py): nesting, size and encoding bounded,
errors one line naming line and column."""

from __future__ import annotations

import pytest

from tests.support.cli import papf


@pytest.mark.parametrize("text,match", [("a = " + "[" * 5000 + "]" * 5000, "nested too deeply"),
                                        ("# " + "x" * (2 * 1024 * 1024), "bytes; a settings file"),
                                        ("\xff\xfe", "not a readable TOML"),
                                        ("d_o = nan", "d_o=nan")])
def test_a_hostile_params_file_is_one_line(tmp_path, text, match):
    from common.errors import ConfigError
    from nodes.planner.registry import load_params

    f = tmp_path / "p.toml"
    f.write_text(text, encoding="latin-1" if text.startswith("\xff") else "utf-8")
    with pytest.raises(ConfigError, match=match):
        load_params("papf", f)
    with pytest.raises(ConfigError, match="no such file"):
        load_params("papf", tmp_path)      # a directory where a file is expected


@pytest.mark.parametrize("what", ["profile", "map", "pub"])
def test_thousands_of_nested_brackets_are_one_line(tmp_path, what):
    from common.errors import PapfError

    deep = "[" * 5000 + "]" * 5000
    with pytest.raises(PapfError, match="nested too deeply"):
        if what == "profile":
            from papf.launch.profile import load_profile

            (tmp_path / "p.toml").write_text(f"a = {deep}\n")
            load_profile(str(tmp_path / "p.toml"))
        elif what == "map":
            from worlds.maps import load_map

            (tmp_path / "m.yaml").write_text(f"image: {deep}\n")
            load_map(tmp_path / "m.yaml")
        else:
            from papf.bus.fields import parse_value

            parse_value(deep)


def test_a_binary_launch_profile_is_one_line(tmp_path):
    from common.errors import ConfigError
    from papf.launch.profile import load_profile

    (tmp_path / "p.toml").write_bytes(b"\xff\xfe\x00\x01" * 100)
    with pytest.raises(ConfigError, match="cannot read it as UTF-8"):
        load_profile(str(tmp_path / "p.toml"))


@pytest.mark.parametrize("kind", ["params", "profile"])
def test_broken_settings_and_profiles_name_line_and_column(tmp_path, kind):
    if kind == "params":
        f = tmp_path / "p.toml"
        f.write_text("v_max = 0.3\nd_o = \n")
        res = papf("plan", "--world", "energy", "--params", str(f))
    else:
        f = tmp_path / "prof.toml"
        f.write_text('name = "x"\nrouter = tru\n')
        res = papf("launch", str(f))
    assert res.returncode == 2 and "is not valid TOML: line 2, column" in res.stderr
