"""nodes/ros_face/navigate.py and params.py, pure: Nav2's action and ROS 2 parameters on our
planner. Requests are built and responses read with the tests' own rosbags store
(tests/support/rmw_client.py), not the module's codec."""

from __future__ import annotations

import json

import numpy as np
import pytest

from common.errors import SchemaError
from nodes.planner.params import answer
from nodes.planner.registry import make_planner
from nodes.ros_face.navigate import (
    ABORTED,
    CANCELED,
    EXECUTING,
    SUCCEEDED,
    UNKNOWN,
    Navigator,
)
from nodes.ros_face.params import ParamServer, list_names
from schemas import Goal, Odometry, PlannerState, PlannerStatus
from tests.support.rmw_client import NAV, Client

C = Client(None, 0)
P = "rcl_interfaces/srv/"


def enc(typename, msg) -> bytes:
    return bytes(C.store.serialize_cdr(msg, typename))


def dec(typename, data):
    return C.store.deserialize_cdr(data, typename)


class Held:
    """A get_result reply kept until the goal ends."""
    def __init__(self):
        self.sent = []

    def send(self, data):
        self.sent.append(data)


def send(nav, x, y, frame="map"):
    gid, req = C.goal_request(x, y, frame)
    resp, goal, replies = nav.send_goal(enc(NAV + "_SendGoal_Request", req))
    return gid, dec(NAV + "_SendGoal_Response", resp).accepted, goal, replies


def status(state, t, reason=""):
    return PlannerStatus(stamp_ns=t, state=state, reason=reason)


def result_of(nav, gid, held=None):
    req = enc(NAV + "_GetResult_Request", C.msg(NAV + "_GetResult_Request", goal_id=C.uuid(gid)))
    now = nav.get_result(req, held or Held())
    return [dec(NAV + "_GetResult_Response", cdr) for _r, cdr in now]


def test_a_goal_runs_to_success_with_feedback_and_held_results():
    nav = Navigator()
    nav.on_goal(Goal(stamp_ns=0, x=5.0, y=0.0, tolerance=0.3))
    gid, ok, goal, _ = send(nav, 2.0, 1.0)
    assert ok and (goal.x, goal.y, goal.tolerance, goal.cancel) == (2.0, 1.0, 0.3, False)
    held = Held()
    assert result_of(nav, gid, held) == []                       # held until the goal ends
    nav.on_status(status("ready", 0))
    assert nav.goals[gid].status == EXECUTING
    fb = nav.on_odom(Odometry(stamp_ns=500_000_000, x=1.0, y=1.0, yaw=0.0, v=0.5, w=0.0))
    f = dec(NAV + "_FeedbackMessage", fb)
    assert bytes(f.goal_id.uuid) == gid and f.feedback.distance_remaining == pytest.approx(1.0)
    assert f.feedback.navigation_time.nanosec == 500_000_000 and f.feedback.current_pose.header.frame_id == "map"
    assert f.feedback.estimated_time_remaining.sec == 2
    assert nav.on_odom(Odometry(stamp_ns=550_000_000, x=1.0, y=1.0, yaw=0.0, v=0.5, w=0.0)) is None
    nav.on_state(PlannerState(stamp_ns=1, algorithm="papf", mode="drive"))
    nav.on_state(PlannerState(stamp_ns=2, algorithm="papf", mode="bypass"))
    nav.on_state(PlannerState(stamp_ns=3, algorithm="papf", mode="drive"))
    assert nav.goals[gid].recoveries == 1
    (reply, cdr), = nav.on_status(status("reached", 2_000_000_000))
    assert reply is held and dec(NAV + "_GetResult_Response", cdr).status == SUCCEEDED
    (later,) = result_of(nav, gid)
    assert later.status == SUCCEEDED and later.result.error_code == 0
    arr = dec("action_msgs/msg/GoalStatusArray", nav.status_array())
    assert [(bytes(s.goal_info.goal_id.uuid), s.status) for s in arr.status_list] == [(gid, SUCCEEDED)]


def test_preempt_cancel_and_refusals():
    nav = Navigator()
    a, _ok, _g, _ = send(nav, 3.0, 0.0)
    nav.on_status(status("driving", 10))
    b, ok, _g, replies = send(nav, 1.0, 0.0, frame="odom")
    assert ok and nav.goals[a].status == ABORTED and replies == []
    assert "preempted" in result_of(nav, a)[0].result.error_msg
    nav.on_status(status("reached", 5))                          # the old goal's, before b's ack
    assert nav.goals[b].status != SUCCEEDED
    req = C.msg("action_msgs/srv/CancelGoal_Request", goal_info=C.msg(
        "action_msgs/msg/GoalInfo", goal_id=C.uuid(b), stamp=C.time()))
    resp, stop = nav.cancel_goal(enc("action_msgs/srv/CancelGoal_Request", req))
    assert dec("action_msgs/srv/CancelGoal_Response", resp).return_code == 0
    assert stop.cancel and (stop.x, stop.y) == (1.0, 0.0)
    nav.on_status(status("idle", 20, "goal canceled"))
    assert result_of(nav, b)[0].status == CANCELED
    again, _ = nav.cancel_goal(enc("action_msgs/srv/CancelGoal_Request", req))
    assert dec("action_msgs/srv/CancelGoal_Response", again).return_code == 3     # terminated
    unknown = C.msg("action_msgs/srv/CancelGoal_Request", goal_info=C.msg(
        "action_msgs/msg/GoalInfo", goal_id=C.uuid(bytes(range(16))), stamp=C.time()))
    resp, _ = nav.cancel_goal(enc("action_msgs/srv/CancelGoal_Request", unknown))
    assert dec("action_msgs/srv/CancelGoal_Response", resp).return_code == 2
    assert result_of(nav, bytes(range(16)))[0].status == UNKNOWN
    assert not send(nav, 1.0, 0.0, frame="base_link")[1]         # not the world frame
    assert not send(nav, float("nan"), 0.0)[1]
    assert not send(Navigator(accept=False), 1.0, 0.0)[1]       # a lockstep run
    with pytest.raises(SchemaError):
        nav.send_goal(b"\x00\x01\x00\x00\x01")


def test_humble_result_is_empty():
    h = Client(None, 0, "humble")
    nav = Navigator("humble")
    gid, req = h.goal_request(1.0, 0.0)
    nav.send_goal(bytes(h.store.serialize_cdr(req, NAV + "_SendGoal_Request")))
    nav.on_status(status("ready", 0))
    held = Held()
    nav.get_result(bytes(h.store.serialize_cdr(h.msg(NAV + "_GetResult_Request", goal_id=h.uuid(gid)),
                                               NAV + "_GetResult_Request")), held)
    (_r, cdr), = nav.on_status(status("stagnated", 1, "stuck"))
    msg = h.store.deserialize_cdr(cdr, NAV + "_GetResult_Response")
    assert msg.status == ABORTED and hasattr(msg.result, "result")   # std_msgs/Empty


# -- parameters --------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def planner():
    return make_planner("papf")


def server(planner, writable=True):
    def ask(request, signed):
        reply, _changed = answer("papf", planner, json.dumps(request).encode())
        return reply
    return ParamServer(ask, writable)


def call(ps, service, srv, **fields):
    resp, changed = ps.handle(service, enc(P + srv + "_Request", C.msg(P + srv + "_Request", **fields)))
    return dec(P + srv + "_Response", resp), changed


def value(kind, **v):
    base = dict(type=kind, bool_value=False, integer_value=0, double_value=0.0, string_value="",
                byte_array_value=np.zeros(0, np.uint8), bool_array_value=np.zeros(0, bool),
                integer_array_value=np.zeros(0, np.int64), double_array_value=np.zeros(0),
                string_array_value=[])
    return C.msg("rcl_interfaces/msg/ParameterValue", **{**base, **v})


def param(name, kind, **v):
    return C.msg("rcl_interfaces/msg/Parameter", name=name, value=value(kind, **v))


def test_parameters_list_get_describe_set(planner):
    ps = server(planner)
    listed, _ = call(ps, "list_parameters", "ListParameters", prefixes=[], depth=0)
    assert "apf.v_max" in listed.result.names and set(listed.result.prefixes) == {"apf", "papf"}
    got, _ = call(ps, "get_parameters", "GetParameters", names=["apf.v_max", "apf.lidar_points"])
    assert (got.values[0].type, got.values[1].type) == (3, 2)
    types, _ = call(ps, "get_parameter_types", "GetParameterTypes", names=["apf.v_max", "x"])
    assert list(types.types) == [3, 0]
    d, _ = call(ps, "describe_parameters", "DescribeParameters", names=["apf.lidar_points"])
    assert d.descriptors[0].integer_range[0].from_value == 1 and not d.descriptors[0].read_only
    res, changed = call(ps, "set_parameters", "SetParameters", parameters=[
        param("apf.v_max", 3, double_value=0.3), param("apf.d_o", 3, double_value=0.1),
        param("apf.lidar_points", 3, double_value=2.0),
        param("nope", 3, double_value=1.0), param("apf.v_max", 0)])
    ok, floor, int_as_double, unknown, unset = res.results
    assert ok.successful and changed == ["apf.v_max"] and planner.apf.v_max == 0.3
    assert not floor.successful and "apf.d_o" in floor.reason and "0.25" in floor.reason
    assert not int_as_double.successful and "integer" in int_as_double.reason
    assert not unknown.successful and not unset.successful and "undeclared" in unset.reason
    atomic, changed = call(ps, "set_parameters_atomically", "SetParametersAtomically", parameters=[
        param("apf.v_max", 3, double_value=0.25), param("apf.d_o", 3, double_value=0.0)])
    assert not atomic.result.successful and changed == []        # all or nothing


def test_read_only_when_the_face_refuses(planner):
    ps = server(planner, writable=False)
    d, _ = call(ps, "describe_parameters", "DescribeParameters", names=["apf.v_max"])
    assert d.descriptors[0].read_only
    res, changed = call(ps, "set_parameters", "SetParameters",
                        parameters=[param("apf.v_max", 3, double_value=0.3)])
    assert not res.results[0].successful and "read-only" in res.results[0].reason and not changed


def test_list_names_follows_rclcpp():
    names = ["a", "b.c", "b.d.e", "f.g"]
    assert list_names(names, [], 0) == (names, ["b", "b.d", "f"])
    assert list_names(names, [], 1) == (["a"], [])
    assert list_names(names, ["b"], 0) == (["b.c", "b.d.e"], ["b", "b.d"])
    assert list_names(names, ["b"], 1) == ([], [])              # rclcpp counts the "." after b
    assert list_names(names, ["b"], 2) == (["b.c"], ["b"])
