"""The secure split's access rules (pure) and `papf certs` refusing to replace a bundle or take bad hosts."""

from __future__ import annotations

import shutil
import sys

import pytest

from nodes.base_driver.rosbot import BridgeTopics
from papf.robot.certs import ROLES, access_control

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
    import subprocess

    def certs(*args):
        return subprocess.run([sys.executable, "-m", "papf", "make-certs", *map(str, args)],
                              capture_output=True, text=True, timeout=60)

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
