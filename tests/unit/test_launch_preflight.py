"""One preflight for run and launch (papf/launch/preflight.py): everything ``papf run`` refuses
``papf launch`` refuses too, before any process starts — settings, worlds, recordings, Zenoh
configs, the bridge's namespace, the view port, planner names."""

from __future__ import annotations

import math

import pytest

from common.errors import ConfigError, WorldError
from papf.launch.preflight import check_launch
from papf.launch.profile import load_profile
from worlds.validate import MAX_OBSTACLES


def _launch(**kw):
    from papf.launch.profile import LaunchOptions

    values = {"world": "energy", **kw.pop("values", {})}
    return LaunchOptions(kw.pop("profile", "sim"), values=values, **kw)


def _config_cases(tmp_path):
    bad = tmp_path / "bad.json5"
    bad.write_text("{ mode: 'router', listen: { endpoints: [ ")
    big = tmp_path / "big.json5"
    big.write_bytes(b" " * (2 * 1024 * 1024))
    binary = tmp_path / "bin.json5"
    binary.write_bytes(b"\xff\xfe\x00garbage")
    return [(str(tmp_path / "missing.json5"), "does not exist"), (str(tmp_path), "is a directory"),
            (str(bad), "not a valid Zenoh JSON5"), (str(big), "bytes is not a Zenoh config"),
            (str(binary), "not a valid Zenoh JSON5")]


def test_launch_refuses_a_bad_router_or_node_config_before_anything_starts(tmp_path):
    from common.errors import ConfigError
    from papf.launch.preflight import check_launch
    from papf.launch.profile import load_profile

    for path, match in _config_cases(tmp_path):
        for opt in (_launch(router_config=path), _launch(zenoh_config=path)):
            with pytest.raises(ConfigError, match=match):
                check_launch(opt, load_profile("sim"))
    good = tmp_path / "good.json5"
    good.write_text('{"mode": "router"}')
    check_launch(_launch(router_config=str(good)), load_profile("sim"))


@pytest.mark.parametrize("ns,match", [("a//b", "plain key"), ("lab/*", "plain key"),
                                      ("has space", "plain key"), ("rosbot", "overlaps")])
def test_launch_refuses_a_bridge_namespace_that_makes_no_key(ns, match):
    from common.errors import ConfigError
    from papf.launch.preflight import check_launch
    from papf.launch.profile import load_profile

    with pytest.raises(ConfigError, match=match):
        check_launch(_launch(values={"bridge_namespace": ns}), load_profile("sim"))


def test_a_busy_or_out_of_range_view_port_is_refused_before_anything_starts(capsys):
    import socket

    from common.errors import ConfigError
    from papf.cli import main
    from papf.launch.preflight import check_launch
    from papf.launch.profile import load_profile

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        busy = s.getsockname()[1]
        with pytest.raises(ConfigError, match=f"--view {busy}: something already listens"):
            check_launch(_launch(values={"view": busy}), load_profile("sim"))
    for bad in ("99999", "0", "nan", "-1"):
        with pytest.raises(SystemExit) as exc:
            main(["launch", "sim", "--view", bad])
        assert exc.value.code == 2 and "--view" in capsys.readouterr().err


def test_check_errors_are_config_errors():
    from papf.launch.preflight import planner_name

    with pytest.raises(ConfigError, match="did you mean 'arapf'"):
        planner_name("ARAPF")


@pytest.mark.parametrize("opt,match", [
    (_launch(timeout_s=math.nan), "--timeout=nan"),
    (_launch(namespace="a//b"), "--namespace"),
    (_launch(listen=["tcp/127.0.0.1:99999"]), "port '99999'"),
    (_launch(listen=["tcp/[::1"]), "must look like"),
    (_launch(values={"seed": -1}), "--seed=-1"),
    (_launch(planner_args=["--set", "d_o=nan"]), "d_o=nan"),
    (_launch(values={"planner": "papff"}), "did you mean 'papf'"),
    (_launch(values={"world": "wang-3d-fig9"}), "3-D"),
])
def test_launch_makes_the_checks_run_makes(opt, match):
    with pytest.raises((ConfigError, WorldError), match=match):
        check_launch(opt, load_profile("sim"))


def test_launch_refuses_worlds_run_refuses(tmp_path):
    head = '[goal]\nposition = [{gx}, {gy}]\n'
    many = head.format(gx=10.0, gy=0.0) + "".join(
        f'[[obstacles]]\nkind = "cylinder"\ncenter = [{20.0 + i * 0.3}, 20.0]\nradius = 0.1\n'
        for i in range(MAX_OBSTACLES + 1))
    inside = head.format(gx=5.0, gy=0.0) + \
        '[[obstacles]]\nkind = "cylinder"\ncenter = [5.0, 0.0]\nradius = 0.25\n'
    for text, match in ((many, "obstacles"), (inside, "goal")):
        f = tmp_path / "w.toml"
        f.write_text(text)
        with pytest.raises(WorldError, match=match):
            check_launch(_launch(values={"world": str(f)}), load_profile("sim"))


def test_launch_refuses_an_existing_recording_unless_forced(tmp_path):
    rec = tmp_path / "a.mcap"
    rec.write_bytes(b"user's")
    with pytest.raises(ConfigError, match="already exists"):
        check_launch(_launch(values={"record": str(rec)}), load_profile("sim"))
    check_launch(_launch(values={"record": str(rec), "record_force": "1"}), load_profile("sim"))
