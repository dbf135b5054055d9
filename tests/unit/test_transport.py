"""Transport configuration: defaults, command-line arguments, bad config files."""

import argparse

import pytest

from common.errors import ConfigError
from common.transport import add_zenoh_args, zenoh_config


def test_config_defaults_to_embedded_router_client():
    conf = zenoh_config()
    assert '"client"' in conf.get_json("mode")
    assert "7447" in conf.get_json("connect/endpoints")
    assert conf.get_json("scouting/multicast/enabled") == "false"


def test_config_from_cli_args():
    p = argparse.ArgumentParser()
    add_zenoh_args(p)
    a = p.parse_args(["--mode", "peer", "--listen", "tcp/127.0.0.1:9000", "--namespace", "r2"])
    assert a.mode == "peer" and a.namespace == "r2" and a.listen == ["tcp/127.0.0.1:9000"]


def test_bad_config_file_is_a_config_error(tmp_path):
    bad = tmp_path / "z.json5"
    bad.write_text("{ this is : not json5 ")
    with pytest.raises(ConfigError, match="cannot read Zenoh config"):
        zenoh_config(config_file=str(bad))
    with pytest.raises(ConfigError, match="mode"):
        zenoh_config(mode="satellite")
