"""The secure split's access rules (pure) and `papf certs` refusing to replace a bundle or take bad hosts."""

from __future__ import annotations

import shutil

import pytest

from common.ros_link import BridgeTopics
from papf.robot.certs import ROLES, access_control
from tests.support.cli import papf

NS, BRIDGE = "t5sec", "bot"


def test_access_control_rules_follow_the_roles():
    acl = access_control(NS, BridgeTopics(BRIDGE))
    assert acl["default_permission"] == "deny"
    puts = {r["id"]: r["key_exprs"] for r in acl["rules"] if r["id"].endswith("-puts")}
    assert puts["planner-puts"].count(f"{NS}/cmd_vel") == 1
    assert f"{BRIDGE}/cmd_vel" in puts["robot-puts"] and f"{NS}/cmd_vel" not in puts["robot-puts"]
    assert "observer-puts" not in puts                      # read-only
    cmd_rules = [rid for rid, keys in puts.items() if any(k.endswith("cmd_vel") for k in keys)]
    assert sorted(cmd_rules) == ["planner-puts", "robot-puts"]
    assert set(ROLES) == {s["usernames"][0] for s in acl["subjects"]}
    receive = next(r for r in acl["rules"] if r["id"] == "receive")
    assert receive["flows"] == ["egress"]                   # everyone may read, nobody writes by it


def test_make_certs_refuses_to_replace_a_bundle_and_bad_hosts(tmp_path):
    if shutil.which("openssl") is None:
        pytest.skip("the openssl command is needed to make test certificates")

    def certs(*args):
        return papf("make-certs", *map(str, args), timeout=60)

    out = tmp_path / "b"
    p = certs(out, "--robot-host", "10.0.0.2")
    assert p.returncode == 0 and "Copy to the robot:" in p.stderr
    ca = (out / "ca.pem").read_bytes()
    assert not any(str(tmp_path) in f.read_text() for f in out.glob("*.json5"))  # relative
    p = certs(out, "--robot-host", "10.0.0.2")
    assert p.returncode == 2 and "--force" in p.stderr and (out / "ca.pem").read_bytes() == ca
    assert certs(out, "--robot-host", "10.0.0.2", "--force").returncode == 0
    assert (out / "ca.pem").read_bytes() != ca
    for host in ("bad host;x", "a..b", "-x", "$(reboot)"):
        p = certs(tmp_path / "c", f"--robot-host={host}")
        assert p.returncode == 2 and "is not an IP address or a DNS name" in p.stderr, host
    assert not (tmp_path / "c").exists()


def test_rmw_zenoh_rules_give_the_ros_domain_to_the_robot_only():
    acl = access_control(NS, BridgeTopics(BRIDGE), ros_domain=4)
    puts = {r["id"]: r["key_exprs"] for r in acl["rules"] if r["id"].endswith("-puts")}
    assert "4/**" in puts["robot-puts"] and f"{BRIDGE}/cmd_vel" not in puts["robot-puts"]
    assert not any(k.startswith("4/") for k in puts["planner-puts"])   # no way past the driver
    talk = next(r for r in acl["rules"] if r["id"] == "talk")
    assert "@ros2_lv/**" in talk["key_exprs"] and "liveliness_token" in talk["messages"]


def test_make_certs_for_rmw_zenoh_writes_rmw_zenohs_config_files(tmp_path):
    """rmw_zenohd's and the ROS 2 nodes' configs, shaped as rmw_zenoh's defaults
    (DEFAULT_RMW_ZENOH_ROUTER_CONFIG.json5 / _SESSION_CONFIG.json5), made secure."""
    if shutil.which("openssl") is None:
        pytest.skip("the openssl command is needed to make test certificates")
    import json

    out = tmp_path / "b"
    p = papf("make-certs", str(out), "--robot-host", "10.0.0.2", "--ros", "rmw_zenoh",
             "--ros-domain", "3", timeout=60)
    assert p.returncode == 0, p.stderr
    assert "ZENOH_ROUTER_CONFIG_URI=rmw_zenohd.json5" in p.stderr
    assert "rmw_zenohd.json5 ros_session.json5" in (out / "README.txt").read_text()
    rmwd = json.loads((out / "rmw_zenohd.json5").read_text())
    assert rmwd["mode"] == "router" and rmwd["listen"]["endpoints"] == [
        "tcp/127.0.0.1:7447", "tls/0.0.0.0:7448"]              # loopback, not tcp/[::]:7447
    assert rmwd["scouting"]["gossip"]["enabled"] and not rmwd["scouting"]["multicast"]["enabled"]
    assert rmwd["transport"]["link"]["tls"]["enable_mtls"]
    assert any("3/**" in r["key_exprs"] for r in rmwd["access_control"]["rules"])
    session = json.loads((out / "ros_session.json5").read_text())
    assert session["mode"] == "peer" and session["connect"]["endpoints"] == ["tcp/127.0.0.1:7447"]
    assert session["transport"]["auth"]["usrpwd"]["user"] == "robot"
    ours = json.loads((out / "router.json5").read_text())
    assert ours["connect"]["endpoints"] == ["tcp/127.0.0.1:7447"]
    assert ours["listen"]["endpoints"] == ["tcp/127.0.0.1:7449"] and "access_control" not in ours
    laptop = json.loads((out / "laptop.json5").read_text())
    assert laptop["connect"]["endpoints"] == ["tls/10.0.0.2:7448"]
    p = papf("make-certs", str(out), "--robot-host", "10.0.0.2", "--force", timeout=60)
    assert p.returncode == 0 and not (out / "rmw_zenohd.json5").exists()   # a bridge bundle now


def test_make_certs_never_writes_secrets_through_a_planted_symlink(tmp_path):
    import os
    import stat

    from common.errors import ConfigError
    from papf.robot.certs import write_bundle

    out = tmp_path / "bundle"
    out.mkdir(mode=0o700)
    stolen = tmp_path / "stolen.txt"
    (out / "credentials.txt").symlink_to(stolen)          # dangling: exists() said "no bundle"
    with pytest.raises(ConfigError, match="already holds a bundle"):
        write_bundle(out, ["10.0.0.1"])
    write_bundle(out, ["10.0.0.1"], force=True)
    assert not stolen.exists() and not (out / "credentials.txt").is_symlink()
    for f in out.iterdir():
        assert stat.S_IMODE(f.stat().st_mode) & 0o077 == 0, f.name
    shared = tmp_path / "shared"
    shared.mkdir()
    os.chmod(shared, 0o777)
    with pytest.raises(ConfigError, match="every user may write in it"):
        write_bundle(shared, ["10.0.0.1"])


def test_the_observer_may_not_query():
    acl = access_control()
    policies = {p["id"]: p["rules"] for p in acl["policies"]}
    rules = {r["id"]: r for r in acl["rules"]}
    assert "query" not in policies["observer"] and "query" in policies["planner"]
    assert all("query" not in rules[r]["messages"] for r in policies["observer"])
