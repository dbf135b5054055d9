"""The ROS 2 graph as papf node/topic info read it, from text written by upstream, not by us.

- rmw_zenoh: the liveliness tokens of ros2/rmw_zenoh ``docs/design.md`` ("Graph Cache",
  "Examples using the demo_nodes_cpp package": listener NN and MS, talker MP,
  add_two_ints_server SS, add_two_ints_client SC), whose format is ``Entity::Entity`` in
  ``rmw_zenoh_cpp/src/detail/liveliness_utils.cpp`` lines 395-445 (@bfc065f); a service's
  type without ``Response_`` per ``rmw_service_data.cpp`` lines 96-108.
- zenoh-bridge-ros2dds (eclipse-zenoh/zenoh-plugin-ros2dds @09d68c0): admin key
  ``@/<zid>/ros2/`` (``lib.rs`` line 131) + ``node/<node id>`` (``discovered_entities.rs``
  line 41), node id ``<participant GID hex><namespace>[/]<name>`` (``node_info.rs`` lines
  414-462, the GID as 32 hex digits by ``gid.rs`` lines 91-100), value the serde JSON of
  ``NodeInfo`` (``node_info.rs`` lines 360-392: field order, ``{"name", "type"}`` items of
  lines 24-29, types by ``dds_type_to_ros2_message_type``, ``ros2_utils.rs`` lines 130-137).
"""

from __future__ import annotations

import pytest

from common import rmw_zenoh as rz
from common.errors import SchemaError
from papf.bus.graph import (
    bridge_topic_info,
    parse_bridge_node,
    ros_node_info,
    ros_nodes,
    ros_topic_info,
)
from papf.robot.bridge_admin import node_json, node_key

STRING = "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18"
ADD_TWO_INTS = "RIHS01_e118de6bf5eeb66a2491b5bda11202e7b68f198d6f67922cf30364858239c81a"
DESIGN_MD_TOKENS = [   # rmw_zenoh docs/design.md, verbatim
    "@ros2_lv/2/aac3178e146ba6f1fc6e6a4085e77f21/0/0/NN/%/%/listener",
    "@ros2_lv/2/aac3178e146ba6f1fc6e6a4085e77f21/0/10/MS/%/%/listener/%chatter/"
    f"std_msgs::msg::dds_::String_/{STRING}/::,10:,:,:,,",
    "@ros2_lv/2/8b20917502ee955ac4476e0266340d5c/0/10/MP/%/%/talker/%chatter/"
    f"std_msgs::msg::dds_::String_/{STRING}/::,7:,:,:,,",
    "@ros2_lv/2/f9980ee0495eaafb3e38f0d19e2eae12/0/10/SS/%/%/add_two_ints_server/%add_two_ints/"
    f"example_interfaces::srv::dds_::AddTwoInts_/{ADD_TWO_INTS}/::,10:,:,:,,",
    "@ros2_lv/2/e1dc8d1b45ae8717fce78689cc655685/0/10/SC/%/%/add_two_ints_client/%add_two_ints/"
    f"example_interfaces::srv::dds_::AddTwoInts_/{ADD_TWO_INTS}/::,10:,:,:,,",
]
GID = "0110c2f9a7d4f2c1b6a2e9d800000000"   # a participant GUID prefix + entity id, as hex
BRIDGE = "8c1e7a55bd1f9d2d"
FIRMWARE_KEY = f"@/{BRIDGE}/ros2/node/{GID}/rosbot_base_controller"
FIRMWARE_JSON = (b'{"publishers":[{"name":"/odometry/wheels","type":"nav_msgs/msg/Odometry"}],'
                 b'"subscribers":[{"name":"/cmd_vel","type":"geometry_msgs/msg/Twist"}],'
                 b'"service_servers":[{"name":"/rosbot_base_controller/get_parameters",'
                 b'"type":"rcl_interfaces/srv/GetParameters"}],"service_clients":[],'
                 b'"action_servers":[],"action_clients":[]}')
EKF_KEY = f"@/{BRIDGE}/ros2/node/{GID}/robot1/ekf_filter_node"
EKF_JSON = (b'{"publishers":[{"name":"/robot1/odometry/filtered","type":"nav_msgs/msg/Odometry"}],'
            b'"subscribers":[],"service_servers":[],"service_clients":[],"action_servers":[],'
            b'"action_clients":[],"undiscovered_writer":["0110c2f9a7d4f2c1b6a2e9d800000703"]}')


def test_rmw_zenoh_graph_from_design_md_tokens():
    entities = [rz.Entity.parse(t) for t in DESIGN_MD_TOKENS]
    assert ros_nodes(entities) == ["/listener"]          # only listener's NN is in the set
    server = ros_node_info(entities, "/add_two_ints_server")
    assert [e.topic for e in server["service servers"]] == ["/add_two_ints"]
    assert server["service servers"][0].typename == "example_interfaces/srv/AddTwoInts"
    assert server["service servers"][0].qos.describe() == "reliable, volatile, keep last 10"
    client = ros_node_info(entities, "/add_two_ints_client")["service clients"]
    assert [(e.kind, e.hash) for e in client] == [(rz.CLIENT, ADD_TWO_INTS)]
    chatter = ros_topic_info(entities, "/chatter")
    assert [e.fq_node for e in chatter["publishers"]] == ["/talker"]
    assert [e.fq_node for e in chatter["subscriptions"]] == ["/listener"]
    assert chatter["publishers"][0].qos.depth == 7
    # and our encoder writes each of them back, byte for byte
    assert [e.token() for e in entities] == DESIGN_MD_TOKENS


def test_bridge_admin_space_nodes():
    fw = parse_bridge_node(FIRMWARE_KEY, FIRMWARE_JSON)
    assert (fw.bridge, fw.participant, fw.name) == (BRIDGE, GID, "/rosbot_base_controller")
    assert fw.interfaces["subscribers"] == (("/cmd_vel", "geometry_msgs/msg/Twist"),)
    assert fw.interfaces["service_servers"] == (("/rosbot_base_controller/get_parameters",
                                                 "rcl_interfaces/srv/GetParameters"),)
    ekf = parse_bridge_node(EKF_KEY, EKF_JSON)          # a namespaced node, extra fields ignored
    assert ekf.name == "/robot1/ekf_filter_node"
    info = bridge_topic_info([fw, ekf], "/cmd_vel")
    assert info == {"publishers": [], "subscribers": [("/rosbot_base_controller",
                                                       "geometry_msgs/msg/Twist")]}
    assert bridge_topic_info([fw, ekf], "/robot1/odometry/filtered")["publishers"] == [
        ("/robot1/ekf_filter_node", "nav_msgs/msg/Odometry")]


@pytest.mark.parametrize("key, payload, says", [
    (f"@/{BRIDGE}/ros2/route/topic/pub/cmd_vel", FIRMWARE_JSON, "node key"),
    (f"@/{BRIDGE}/ros2/node/{GID}", FIRMWARE_JSON, "node key"),
    (FIRMWARE_KEY, b"{not json", "not JSON"),
    (FIRMWARE_KEY, b"[]", "JSON object"),
    (FIRMWARE_KEY, b'{"publishers":[{"name":"/x"}]}', "publishers"),
    (FIRMWARE_KEY, b'{"subscribers":"cmd_vel"}', "subscribers"),
])
def test_bridge_admin_space_malformed(key, payload, says):
    with pytest.raises(SchemaError, match=says):
        parse_bridge_node(key, payload)


def test_emulators_admin_answer_is_the_bridges_format():
    """What papf rosbot-emulator answers on the bridge equals upstream's bytes for that node."""
    assert node_key(BRIDGE, GID, "/", "rosbot_base_controller") == FIRMWARE_KEY
    assert node_key(BRIDGE, GID, "/robot1", "ekf_filter_node") == EKF_KEY
    got = node_json({"/odometry/wheels": "nav_msgs/msg/Odometry"},
                    {"/cmd_vel": "geometry_msgs/msg/Twist"})
    assert got == FIRMWARE_JSON.replace(
        b'{"name":"/rosbot_base_controller/get_parameters","type":"rcl_interfaces/srv/'
        b'GetParameters"}', b"")
