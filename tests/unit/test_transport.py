"""Transport configuration: defaults, command-line arguments, bad config files."""

import argparse
import json
import logging
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import msgpack
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from common import transport
from common.errors import ConfigError
from common.transport import Node, add_zenoh_args, zenoh_config
from common.units import MAX_STAMP_NS
from schemas import Keys
from schemas.keys import TOPICS
from schemas.messages import Odometry, Twist
from tests.support.messages import odom as _odom
from tests.support.messages import scan_63 as _scan

FAST = settings(max_examples=150, deadline=None,
                suppress_health_check=[HealthCheck.too_slow])


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


@pytest.mark.parametrize("stamp", [-2**63, -1, MAX_STAMP_NS + 1, 2**64 - 1])
def test_extreme_stamp_is_dropped_and_counted(stamp):
    node = Node("probe", None, Keys("t"), logging.getLogger("probe"))
    assert node.accept("odom", _odom(stamp).to_bytes()) is None
    assert node.accept("scan", _scan(stamp).to_bytes()) is None
    assert node.bad_messages == {"odom": 1, "scan": 1}


def _node() -> Node:
    return Node("probe", None, Keys("t"), logging.getLogger("probe"))


@FAST
@given(topic=st.sampled_from(sorted(TOPICS)), data=st.binary(max_size=256))
def test_node_turns_any_payload_into_a_message_or_a_counted_drop(topic, data):
    node = _node()
    msg = node.accept(topic, data)
    if msg is None:
        assert node.bad_messages[topic] == 1
    else:
        assert isinstance(msg, TOPICS[topic]) and not node.bad_messages


@FAST
@given(stamp=st.integers(-2**63, 2**64 - 1))
def test_a_message_is_acted_on_only_with_a_stamp_in_range(stamp):
    node = _node()
    payload = msgpack.packb({"_type": Odometry.TYPE, "stamp_ns": stamp, "x": 0.0, "y": 0.0,
                             "yaw": 0.0, "v": 0.0, "w": 0.0})
    msg = node.accept("odom", payload)
    assert (msg is not None) == (0 <= stamp <= MAX_STAMP_NS)
    assert node.bad_messages["odom"] == (msg is None)


def test_a_node_whose_stop_cannot_start_its_timer_still_ends_by_the_kernels_alarm():
    """The bound on a node's stop holds even when the stop request itself is stuck (a thread
    that never starts: the interpreter held by a Zenoh call): the alarm is armed first."""
    code = textwrap.dedent("""
        import threading, time
        from common import transport
        threading.Timer.start = lambda self: time.sleep(3600)   # the stuck thread start
        transport.StopRequested(bound_s=1.0).request("test")
        print("request returned")
    """)
    env = {**os.environ, "PAPF_NODE_PROCESS": "1"}
    t0 = time.monotonic()
    proc = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                          timeout=30, cwd=Path(__file__).resolve().parents[2])
    assert proc.returncode == -signal.SIGALRM, proc.stderr[-2000:]
    assert "request returned" not in proc.stdout
    assert time.monotonic() - t0 < 1.0 + transport.ALARM_EXTRA_S + 10.0


def test_the_health_answer_names_the_last_stamps_taken_and_put():
    """What a run's lockstep fault shows (papf/launch/sequence.py ``where_held``): per topic,
    the stamp of the last sample taken (a dropped one moves nothing) and put."""
    node = _node()
    node.accept("odom", _odom(40_000_000).to_bytes())
    node.accept("odom", _odom(-1).to_bytes())                 # dropped: not taken
    node.accept("scan", _scan(20_000_000).to_bytes())

    class Pub:
        def put(self, payload, **_):
            pass

    node._publishers["cmd_vel"] = Pub()
    node.publish("cmd_vel", Twist(stamp_ns=20_000_000, v=0.1, w=0.0))
    health = node.health()
    assert health["heard"] == {"odom": 40_000_000, "scan": 20_000_000}
    assert health["sent"] == {"cmd_vel": 20_000_000}
    assert json.loads(json.dumps(health)) == health
