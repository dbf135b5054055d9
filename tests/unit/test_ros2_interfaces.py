"""common/ros2_interfaces.py and rmw_zenoh's service keys: every type hash against a value
found upstream (not computed by us), humble's constant, the keys and tokens of services."""

from __future__ import annotations

import pytest
from rosbags.typesys import Stores, get_typestore

from common import rmw_zenoh as rz
from common import ros2_interfaces as ri
from common.errors import ConfigError
from tests.support.rmw_client import UPSTREAM


def test_service_hash_method_gives_rmw_zenohs_addtwoints():
    """The method (request, response, event with rosidl's ServiceEventInfo) on the service
    rmw_zenoh's docs/design.md prints: the same hash."""
    store = get_typestore(Stores.ROS2_JAZZY)
    types = ri._service_types("example_interfaces/srv/AddTwoInts", "int64 a\nint64 b",
                              "int64 sum", events=True)
    store.register(types)
    store.fielddefs["service_msgs/msg/ServiceEventInfo"] = ri.typestore().fielddefs[
        "service_msgs/msg/ServiceEventInfo"]
    assert store.hash_rihs01("example_interfaces/srv/AddTwoInts") == UPSTREAM[
        "example_interfaces/srv/AddTwoInts"]


@pytest.mark.parametrize("typename", [t for t in UPSTREAM if "AddTwoInts" not in t])
def test_hashes_equal_the_upstream_ones(typename):
    assert ri.type_hash(typename) == UPSTREAM[typename]
    assert rz.type_hash(typename) == UPSTREAM[typename]


def test_humble_has_no_hashes_and_its_own_nav2_result():
    assert ri.type_hash("nav2_msgs/action/NavigateToPose_SendGoal", "humble") == \
        "TypeHashNotSupported"
    assert rz.topic_key(0, "/cmd_vel", "geometry_msgs/msg/Twist", "humble") == \
        "0/cmd_vel/geometry_msgs::msg::dds_::Twist_/TypeHashNotSupported"
    humble = ri.typestore("humble").fielddefs["nav2_msgs/action/NavigateToPose_Result"][1]
    jazzy = ri.typestore().fielddefs["nav2_msgs/action/NavigateToPose_Result"][1]
    assert [f[0] for f in humble] == ["result"] and [f[0] for f in jazzy] == ["error_code",
                                                                              "error_msg"]
    with pytest.raises(ConfigError, match="iron"):
        ri.check_distro("iron")


def test_service_key_and_token():
    key = rz.topic_key(3, "/papf_planner/list_parameters", "rcl_interfaces/srv/ListParameters")
    assert key == ("3/papf_planner/list_parameters/rcl_interfaces::srv::dds_::ListParameters_/"
                   + ri.type_hash("rcl_interfaces/srv/ListParameters"))
    e = rz.Entity(3, "abcd", 0, 7, rz.SERVICE, "/", "papf_planner",
                  topic="/navigate_to_pose/_action/send_goal",
                  typename="nav2_msgs/action/NavigateToPose_SendGoal",
                  hash=UPSTREAM["nav2_msgs/action/NavigateToPose_SendGoal"], qos=rz.RELIABLE_10)
    assert e.token() == ("@ros2_lv/3/abcd/0/7/SS/%/%/papf_planner/%navigate_to_pose%_action%"
                         "send_goal/nav2_msgs::action::dds_::NavigateToPose_SendGoal_/"
                         f"{UPSTREAM['nav2_msgs/action/NavigateToPose_SendGoal']}/::,10:,:,:,,")
    assert rz.Entity.parse(e.token()) == e
