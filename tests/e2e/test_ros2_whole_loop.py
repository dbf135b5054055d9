"""A ROS 2 / Nav2 user's whole loop over rmw_zenoh, by a client that is not ours.

The client (tests/support/rmw_client.py: raw zenoh, rosbags CDR, keys and hashes from the
upstream conventions, checked against literal upstream hashes) finds the planner's parameter
services and ``navigate_to_pose`` (send_goal, get_result, cancel_goal, feedback, status), a
transient-local ``/map``, ``/joint_states``, ``/clock`` and a best-effort ``/scan`` with
rmw_zenoh's type names and hashes; lists, describes and sets parameters (a set that would
switch safety off is refused with ROS 2's own result); sends a goal, cancels it (the robot
stops), sends another, preempts it with a third, which is reached with feedback on the way.
"""

from __future__ import annotations

import json
import os
import signal
import threading
import time

import pytest
import zenoh
from zenoh.ext import HistoryConfig, declare_advanced_subscriber

from common.transport import zenoh_config
from papf.launch.supervisor import free_port
from tests.support.e2e import start_papf_run
from tests.support.rmw_client import NAV, Client

DOMAIN = 11
P = "rcl_interfaces/srv/"
SUCCEEDED, CANCELED, ABORTED = 4, 5, 6


def _connect(proc, port: int, deadline: float) -> zenoh.Session:
    while time.monotonic() < deadline and proc.poll() is None:
        try:
            return zenoh.open(zenoh_config("client", [f"tcp/127.0.0.1:{port}"]))
        except zenoh.ZError:
            time.sleep(0.5)
    raise AssertionError(proc.stderr.read() if proc.poll() is not None else "no router")


def _until(what, check, deadline: float, step: float = 0.2):
    while time.monotonic() < deadline:
        got = check()
        if got:
            return got
        time.sleep(step)
    raise AssertionError(f"timed out waiting for {what}")


def _params_ready(client: Client):
    try:
        resp, _ = client.call("/papf_planner/list_parameters", P + "ListParameters",
                              client.msg(P + "ListParameters_Request", prefixes=[], depth=0),
                              timeout=3.0)
        return resp
    except AssertionError:
        return None


def _param(client: Client, name: str, kind: int, **value):
    import numpy as np

    v = dict(type=kind, bool_value=False, integer_value=0, double_value=0.0, string_value="",
             byte_array_value=np.zeros(0, np.uint8), bool_array_value=np.zeros(0, bool),
             integer_array_value=np.zeros(0, np.int64), double_array_value=np.zeros(0),
             string_array_value=[])
    v.update(value)
    return client.msg("rcl_interfaces/msg/Parameter", name=name,
                      value=client.msg("rcl_interfaces/msg/ParameterValue", **v))


def check_parameters(client: Client) -> None:
    listed = _params_ready(client)
    assert "apf.v_max" in listed.result.names and "apf" in listed.result.prefixes
    desc, _ = client.call("/papf_planner/describe_parameters", P + "DescribeParameters",
                          client.msg(P + "DescribeParameters_Request", names=["apf.d_o"]))
    d, = desc.descriptors
    assert d.type == 3 and not d.read_only and len(d.floating_point_range) == 1
    assert d.floating_point_range[0].from_value > 0 and "safety" in d.additional_constraints
    req = client.msg(P + "SetParameters_Request", parameters=[
        _param(client, "apf.d_o", 3, double_value=0.0),          # avoidance off: refused
        _param(client, "apf.v_max", 3, double_value=0.35),
        _param(client, "apf.v_max", 4, string_value="fast")])     # a string: wrong type
    res, (seq, _stamp, gid) = client.call("/papf_planner/set_parameters", P + "SetParameters", req)
    assert seq == client.seq and gid == client.gid     # rmw_zenoh's request/response matching
    refused, ok, wrong = res.results
    assert not refused.successful and "apf.d_o" in refused.reason
    assert ok.successful and not wrong.successful and "double" in wrong.reason
    got, _ = client.call("/papf_planner/get_parameters", P + "GetParameters",
                         client.msg(P + "GetParameters_Request", names=["apf.v_max", "nope"]))
    assert (got.values[0].type, got.values[0].double_value, got.values[1].type) == (3, 0.35, 0)


def check_graph(client: Client) -> None:
    tokens = client.tokens()
    for srv, typename in (("%papf_planner%set_parameters", P + "SetParameters"),
                          ("%navigate_to_pose%_action%send_goal", NAV + "_SendGoal"),
                          ("%navigate_to_pose%_action%cancel_goal", "action_msgs/srv/CancelGoal"),
                          ("%navigate_to_pose%_action%get_result", NAV + "_GetResult")):
        name = typename.replace("/srv/", "::srv::dds_::").replace("/action/", "::action::dds_::")
        assert any(f"/SS/%/%/papf_planner/{srv}/{name}_/{client.hash(typename)}/" in t
                   for t in tokens), srv
    topics = {"%scan": "2:", "%map": ":1:", "%joint_states": "", "%clock": "",
              "%navigate_to_pose%_action%status": ":1:", "%navigate_to_pose%_action%feedback": ""}
    for topic, qos in topics.items():
        mine = [t for t in tokens if "/MP/%/%/papf_" in t and f"/{topic}/" in t]
        assert mine and mine[0].rsplit("/", 1)[1].startswith(qos), (topic, mine)


@pytest.mark.e2e
def test_a_nav2_user_tunes_steers_cancels_and_reaches_over_rmw_zenoh():
    port = free_port()
    proc = start_papf_run("--world", "open", "--planner", "apf", "--realtime", "--namespace",
                          "nav1", "--ros-face", "--ros-face-domain", str(DOMAIN), "--timeout", "150",
                          port=port)
    got: dict[str, list] = {"/map": [], "/clock": [], "/joint_states": [], "/scan": [],
                            "/odom": [], "feedback": [], "status": []}
    try:
        deadline = time.monotonic() + 150.0
        session = _connect(proc, port, deadline)
        client = Client(session, DOMAIN)
        s = client.store
        types = {"/map": "nav_msgs/msg/OccupancyGrid", "/clock": "rosgraph_msgs/msg/Clock",
                 "/joint_states": "sensor_msgs/msg/JointState", "/scan": "sensor_msgs/msg/LaserScan",
                 "/odom": "nav_msgs/msg/Odometry",
                 "feedback": NAV + "_FeedbackMessage", "status": "action_msgs/msg/GoalStatusArray"}
        names = {"feedback": "navigate_to_pose/_action/feedback",
                 "status": "navigate_to_pose/_action/status"}

        def keep(t):
            return lambda smp: got[t].append(s.deserialize_cdr(smp.payload.to_bytes(), types[t]))

        _until("the parameter services", lambda: _params_ready(client), deadline, 0.5)
        subs = [declare_advanced_subscriber(session, client.key(names.get(t, t), ty), keep(t),
                                            history=HistoryConfig(detect_late_publishers=True))
                if t in ("/map", "status") else
                session.declare_subscriber(client.key(names.get(t, t), ty), keep(t))
                for t, ty in types.items()]
        check_parameters(client)
        check_graph(client)
        _until("map, clock, joints, scan", lambda: all(got[t] for t in
               ("/map", "/clock", "/joint_states", "/scan")), deadline)
        grid = got["/map"][0]
        assert grid.header.frame_id == "map" and grid.info.width * grid.info.height == len(grid.data)
        assert {n for n in got["/joint_states"][-1].name} == {
            "front_left_wheel_joint", "front_right_wheel_joint", "rear_left_wheel_joint",
            "rear_right_wheel_joint"}

        # goal A: accepted, moving, then cancelled: the robot stops
        a, req = client.goal_request(4.0, 0.0)
        accepted, _ = client.call("navigate_to_pose/_action/send_goal", NAV + "_SendGoal", req)
        assert accepted.accepted
        _until("feedback and motion", lambda: got["feedback"] and got["/odom"] and
               got["/odom"][-1].twist.twist.linear.x > 0.1, deadline)
        fb = got["feedback"][-1]
        assert bytes(fb.goal_id.uuid) == a and 0 < fb.feedback.distance_remaining < 4.1
        cancel, _ = client.call("navigate_to_pose/_action/cancel_goal", "action_msgs/srv/CancelGoal",
                                client.msg("action_msgs/srv/CancelGoal_Request", goal_info=client.msg(
                                    "action_msgs/msg/GoalInfo", goal_id=client.uuid(a),
                                    stamp=client.time())))
        assert cancel.return_code == 0 and bytes(cancel.goals_canceling[0].goal_id.uuid) == a
        result_a, _ = client.call("navigate_to_pose/_action/get_result", NAV + "_GetResult",
                                  client.msg(NAV + "_GetResult_Request", goal_id=client.uuid(a)))
        assert result_a.status == CANCELED
        _until("the robot stopped", lambda: abs(got["/odom"][-1].twist.twist.linear.x) < 0.01,
               deadline)
        x_stop = got["/odom"][-1].pose.pose.position.x
        assert x_stop < 3.5

        # goal B, preempted by goal C; C is reached with feedback on the way
        b, req_b = client.goal_request(x_stop + 2.0, 1.0)
        assert client.call("navigate_to_pose/_action/send_goal", NAV + "_SendGoal", req_b)[0].accepted
        results: dict[bytes, object] = {}

        def wait_result(goal_id):
            results[goal_id] = client.call(
                "navigate_to_pose/_action/get_result", NAV + "_GetResult",
                client.msg(NAV + "_GetResult_Request", goal_id=client.uuid(goal_id)), timeout=120)[0]

        waiter_b = threading.Thread(target=wait_result, args=(b,))
        waiter_b.start()
        time.sleep(1.0)
        c, req_c = client.goal_request(x_stop + 1.5, 0.0, frame="odom")
        assert client.call("navigate_to_pose/_action/send_goal", NAV + "_SendGoal", req_c)[0].accepted
        waiter_b.join(30)
        assert results[b].status == ABORTED and "preempted" in results[b].result.error_msg
        n_feedback = len(got["feedback"])
        wait_result(c)
        assert results[c].status == SUCCEEDED and results[c].result.error_code == 0
        ours = [f for f in got["feedback"][n_feedback:] if bytes(f.goal_id.uuid) == c]
        assert ours and ours[-1].feedback.distance_remaining < ours[0].feedback.distance_remaining
        # The status array is published before the result is answered, but a topic and a
        # query reply travel apart: the client may hold the result before the array arrives.
        def latest_status():
            return {bytes(g.goal_info.goal_id.uuid): g.status
                    for g in got["status"][-1].status_list}

        _until("the status array with C succeeded",
               lambda: latest_status().get(c) == SUCCEEDED, time.monotonic() + 10.0)
        status = latest_status()
        assert (status[a], status[b], status[c]) == (CANCELED, ABORTED, SUCCEEDED)
        assert any(f.feedback.number_of_recoveries >= 0 and f.feedback.navigation_time.sec >= 0
                   for f in ours)
        out, err = proc.communicate(timeout=120)
        for sub in subs:
            sub.undeclare()
        session.close()
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    result = json.loads(out.strip().splitlines()[-1])
    assert result["outcome"] == "reached", err[-3000:]


@pytest.mark.e2e
def test_humble_keys_and_a_face_that_refuses(router, session, spawn):
    """The face on ROS 2 Humble's rmw_zenoh (no type hashes: ``TypeHashNotSupported``) with
    ``--goals refuse`` (a lockstep run's): parameters are listed and read-only, a Nav2 goal
    is refused, and nothing in the graph carries a RIHS01 hash."""
    import sys

    ns, domain = "humble1", DOMAIN + 1
    spawn("planner", [sys.executable, "-m", "nodes.planner", "--planner", "apf", "--connect",
                      router, "--namespace", ns])
    spawn("face", [sys.executable, "-m", "nodes.ros_face", "--connect", router, "--namespace", ns,
                   "--ros-domain", str(domain), "--ros-distro", "humble", "--goals", "refuse"])
    client = Client(session, domain, "humble")
    deadline = time.monotonic() + 90.0
    listed = _until("the parameter services", lambda: _params_ready(client), deadline, 0.5)
    assert "apf.v_max" in listed.result.names
    assert client.key("/papf_planner/list_parameters", P + "ListParameters").endswith(
        "/rcl_interfaces::srv::dds_::ListParameters_/TypeHashNotSupported")
    res, _ = client.call("/papf_planner/set_parameters", P + "SetParameters", client.msg(
        P + "SetParameters_Request", parameters=[_param(client, "apf.v_max", 3, double_value=0.3)]))
    assert not res.results[0].successful and "read-only" in res.results[0].reason
    _gid, req = client.goal_request(1.0, 0.0)
    assert not client.call("navigate_to_pose/_action/send_goal", NAV + "_SendGoal", req)[0].accepted
    tokens = [t for t in client.tokens() if "/papf_" in t and ("/MP/" in t or "/SS/" in t)]
    assert tokens and all("/TypeHashNotSupported/" in t and "RIHS01" not in t for t in tokens)
