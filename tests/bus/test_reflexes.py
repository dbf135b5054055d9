"""papf topic pub|info, papf node list|info over a real router: our keys and rmw_zenoh's graph.

The ROS 2 side is announced by raw liveliness tokens written from rmw_zenoh's format
(ros2/rmw_zenoh liveliness_utils.cpp, ``Entity::Entity``) and read back with raw Zenoh,
not only through our own encoder.
"""

from __future__ import annotations

import subprocess
import sys
import time

import pytest
import zenoh
from rosbags.typesys import Stores, get_typestore

from common.transport import Node
from schemas import Keys, Twist
from tests.support import warm

STORE = get_typestore(Stores.ROS2_JAZZY)
DOMAIN = 11
TWIST_HASH = "RIHS01_9c45bf16fe0983d80e3cfe750d6835843d265a9a6c46bd2e609fcddde6fb8d2a"
ZID = "100f0e0d0c0b0a090807060504030201"
ROBOT_TOKENS = (   # a robot's controller on rmw_zenoh: node, and its /cmd_vel subscription
    f"@ros2_lv/{DOMAIN}/{ZID}/0/0/NN/%/%/controller_manager",
    f"@ros2_lv/{DOMAIN}/{ZID}/0/3/MS/%/%/controller_manager/%cmd_vel/"
    f"geometry_msgs::msg::dds_::Twist_/{TWIST_HASH}/::,10:,:,:,,",
)


def papf(*argv, router, timeout=60):
    return warm.run([sys.executable, "-m", "papf", *argv, "--connect", router], timeout=timeout)


def test_node_list_and_info_on_the_ros_graph(router, session):
    tokens = [session.liveliness().declare_token(t) for t in ROBOT_TOKENS]
    try:
        r = papf("node", "list", "--ros", "rmw_zenoh", "--ros-domain", str(DOMAIN), router=router)
        assert r.returncode == 0, r.stderr
        assert f"/controller_manager  (ROS 2, rmw_zenoh domain {DOMAIN})" in r.stdout
        r = papf("topic", "list", "--duration", "0.5", "--ros", "rmw_zenoh", "--ros-domain",
                 str(DOMAIN), router=router)
        assert r.returncode == 0, r.stderr
        assert f"ROS 2 on rmw_zenoh, domain {DOMAIN}: nodes /controller_manager" in r.stdout
        assert "  /cmd_vel  [geometry_msgs/msg/Twist]" in r.stdout
        r = papf("node", "info", "/controller_manager", "--ros", "rmw_zenoh", "--ros-domain",
                 str(DOMAIN), router=router)
        assert r.returncode == 0, r.stderr
        assert "/cmd_vel: geometry_msgs/msg/Twist (reliable, volatile, keep last 10)" in r.stdout
        r = papf("topic", "info", "/cmd_vel", "-v", "--ros", "rmw_zenoh", "--ros-domain",
                 str(DOMAIN), router=router)
        assert r.returncode == 0, r.stderr
        assert "Subscription count: 1" in r.stdout and "Publisher count: 0" in r.stdout
        assert TWIST_HASH in r.stdout
    finally:
        for t in tokens:
            t.undeclare()
    r = papf("node", "info", "/nobody", "--ros", "rmw_zenoh", "--ros-domain", str(DOMAIN),
             router=router)
    assert r.returncode == 2 and "no ROS 2 node /nobody" in r.stderr


BRIDGE_ZID = "8c1e7a55bd1f9d2d"
BRIDGE_NODE = (   # a bridge's admin-space reply, shaped as tests/unit/test_ros_graph.py cites
    f"@/{BRIDGE_ZID}/ros2/node/0110c2f9a7d4f2c1b6a2e9d800000000/rosbot_base_controller",
    b'{"publishers":[{"name":"/odometry/wheels","type":"nav_msgs/msg/Odometry"}],'
    b'"subscribers":[{"name":"/cmd_vel","type":"geometry_msgs/msg/Twist"}],'
    b'"service_servers":[],"service_clients":[],"action_servers":[],"action_clients":[]}')


def test_node_and_topic_info_behind_the_bridge(router, session):
    """A queryable answering as zenoh-bridge-ros2dds's admin space (raw key and JSON bytes)."""
    key, value = BRIDGE_NODE

    def answer(query):
        if zenoh.KeyExpr(str(query.key_expr)).intersects(zenoh.KeyExpr(key)):
            query.reply(key, value)

    q = session.declare_queryable(f"@/{BRIDGE_ZID}/ros2/**", answer)
    try:
        r = papf("node", "list", router=router)
        assert r.returncode == 0, r.stderr
        assert f"/rosbot_base_controller  (ROS 2, zenoh-bridge-ros2dds {BRIDGE_ZID[:8]})" in r.stdout
        r = papf("node", "info", "/rosbot_base_controller", router=router)
        assert r.returncode == 0, r.stderr
        assert "  Subscribers:\n    /cmd_vel: geometry_msgs/msg/Twist" in r.stdout
        assert "  Publishers:\n    /odometry/wheels: nav_msgs/msg/Odometry" in r.stdout
        r = papf("topic", "info", "/cmd_vel", "-v", router=router)
        assert r.returncode == 0, r.stderr
        assert "Type: geometry_msgs/msg/Twist" in r.stdout
        assert "Subscriber count: 1\n  /rosbot_base_controller  [geometry_msgs/msg/Twist]" in r.stdout
        assert "Publisher count: 0" in r.stdout
    finally:
        q.undeclare()
    r = papf("node", "info", "/rosbot_base_controller", router=router)
    assert r.returncode == 2 and "no ROS 2 node /rosbot_base_controller behind" in r.stderr
    r = papf("topic", "info", "/cmd_vel", router=router)
    assert r.returncode == 2 and "no zenoh-bridge-ros2dds answered" in r.stderr


def test_topic_pub_on_rmw_zenoh_is_what_rmw_zenoh_puts(router, session):
    got, tokens = [], []
    key = f"{DOMAIN}/cmd_vel/geometry_msgs::msg::dds_::Twist_/{TWIST_HASH}"
    sub = session.declare_subscriber(key, lambda s: got.append(
        (STORE.deserialize_cdr(s.payload.to_bytes(), "geometry_msgs/msg/Twist"),
         s.attachment.to_bytes())))
    proc = subprocess.Popen([sys.executable, "-m", "papf", "topic", "pub", "/cmd_vel",
                             "{linear: {x: 0.2}, angular: {z: -0.5}}", "--times", "20", "--rate",
                             "10", "--ros", "rmw_zenoh", "--ros-domain", str(DOMAIN), "--connect",
                             router], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline and not any("/MP/" in t for t in tokens):
        tokens = [str(r.ok.key_expr) for r in session.liveliness().get(
            f"@ros2_lv/{DOMAIN}/**", timeout=1.0) if r.ok]
    out, err = proc.communicate(timeout=60)
    sub.undeclare()
    assert proc.returncode == 0, err
    assert got and got[0][0].linear.x == pytest.approx(0.2) and got[0][0].angular.z == -0.5
    assert [int.from_bytes(a[:8], "little") for _, a in got] == list(range(1, len(got) + 1))
    assert any(t.endswith("/NN/%/%/papf_topic_pub") for t in tokens), tokens
    assert any(f"/MP/%/%/papf_topic_pub/%cmd_vel/geometry_msgs::msg::dds_::Twist_/{TWIST_HASH}/"
               in t for t in tokens), tokens


def test_topic_pub_and_info_on_our_keys(router, session):
    keys = Keys("reflex")
    got = []
    sub = session.declare_subscriber(keys.cmd_vel, lambda s: got.append(
        Twist.from_bytes(s.payload.to_bytes())))
    r = papf("topic", "pub", "cmd_vel", '{"v": 0.3, "w": 0.1, "stamp_ns": 5}', "--once",
             "--namespace", "reflex", router=router)
    sub.undeclare()
    assert r.returncode == 0, r.stderr
    assert got == [Twist(stamp_ns=5, v=0.3, w=0.1)]
    node = Node("planner", session, keys, __import__("logging").getLogger("t"))
    node.ready()
    try:
        r = papf("topic", "info", "cmd_vel", "--namespace", "reflex", router=router)
        assert r.returncode == 0, r.stderr
        assert "Type: papf/Twist/v1" in r.stdout and "Publisher count: 1\n  planner" in r.stdout
        r = papf("node", "info", "planner", "--namespace", "reflex", router=router)
        assert r.returncode == 0 and "reflex/planner: alive" in r.stdout
        assert "out  reflex/cmd_vel" in r.stdout
        r = papf("node", "list", "--namespace", "reflex", router=router)
        assert r.stdout.splitlines() == ["reflex/planner"]
    finally:
        node.close()


@pytest.mark.parametrize("argv, says", [
    (["topic", "pub", "cmd_vel", "{v: fast, w: 0}"], "Twist"),
    (["topic", "pub", "/cmd_vel", "{linar: {x: 1}}"], "no field linar"),
    (["topic", "pub", "/my_topic", "{}"], "--ros-type"),
    (["topic", "pub", "cmd_vel", "[1, 2]"], "mapping of fields"),
    (["topic", "pub", "/cmd_vel", "{}", "--ros", "rmw_zenoh", "--ros-domain", "999"], "0..232"),
    (["topic", "info", "nokey"], "give a stack topic"),
])
def test_user_mistakes_are_one_line_and_exit_2(router, argv, says):
    r = papf(*argv, router=router)
    assert r.returncode == 2 and says in r.stderr and "Traceback" not in r.stderr
