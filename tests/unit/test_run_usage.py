"""`papf run` usage errors: a broken world file is one line and exit 2, before anything starts."""

from tests.support.e2e import papf_run


def test_broken_world_file_is_a_clear_usage_error(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[goal]\nposition = [1]\n")
    code, res, err = papf_run("--world", str(bad))
    assert code == 2 and res is None
    assert "goal.position" in err
