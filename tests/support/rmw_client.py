"""A ROS 2 client on rmw_zenoh that is not ours: raw zenoh-python, rosbags for CDR and hashes.

Written from upstream conventions only, so the face is checked against something other than
its own encoder (no import of ``common.rmw_zenoh``, ``common.ros2_interfaces`` or
``common.ros_link``):

- keys ``<domain>/<name>/<pkg>::<msg|srv|action>::dds_::<Name>_/<hash>`` (rmw_zenoh
  ``liveliness_utils.cpp`` ``TopicInfo``; services: ``rmw_service_data.cpp``, the service
  type without ``Request_``/``Response_``); action services and topics under
  ``<action>/_action/{send_goal,cancel_goal,get_result,feedback,status}`` (rcl_action
  ``names.c``);
- hashes: RIHS01 by rosbags' ``hash_rihs01``; a service's over the type rosidl describes
  (fields ``request_message``, ``response_message``, ``event_message``; the event with
  ``service_msgs/ServiceEventInfo``, whose ``char[16] client_gid`` rosidl types as uint8);
  checked here against literal upstream values (:data:`UPSTREAM`); humble:
  ``TypeHashNotSupported`` (rmw_zenoh PR #388);
- a call: ``get`` on the service key with the request CDR and the attachment (int64
  sequence number, int64 stamp, 16-byte GID as a zenoh-ext sequence: ``z_serialize``),
  the reply's attachment carries the same sequence number and GID (``rmw_client_data.cpp``).
The service and action definitions are written again here from the upstream ``.srv`` and
``.action`` files (ros2/rcl_interfaces jazzy, ros-navigation/navigation2 jazzy and humble).
"""

from __future__ import annotations

import time
import uuid as uuidlib

import numpy as np
import zenoh
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from zenoh.ext import Int64, z_deserialize, z_serialize

# literal hashes found upstream: rmw_zenoh docs/design.md (AddTwoInts), a captured rclcpp
# talker's tokens (ParameterEvent), rosidl's generated nav2_msgs navigate_to_pose__description.c
UPSTREAM = {
    "example_interfaces/srv/AddTwoInts":
        "RIHS01_e118de6bf5eeb66a2491b5bda11202e7b68f198d6f67922cf30364858239c81a",
    "rcl_interfaces/msg/ParameterEvent":
        "RIHS01_043e627780fcad87a22d225bc2a037361dba713fca6a6b9f4b869a5aa0393204",
    "action_msgs/msg/GoalStatusArray":
        "RIHS01_6c1684b00f177d37438febe6e709fc4e2b0d4248dca4854946f9ed8b30cda83e",
    "nav2_msgs/action/NavigateToPose_SendGoal":
        "RIHS01_a4fcb3bee1bf32e21a0e541a943b221aa0826996e2c98f079b47022b256f48b5",
    "nav2_msgs/action/NavigateToPose_GetResult":
        "RIHS01_c407920357d566771e8882b4ef4d1f1a84ee922d609920ccd57faa6d6e391dc5",
    "nav2_msgs/action/NavigateToPose_FeedbackMessage":
        "RIHS01_9d1f6fa2eb975ce733b419ac2e97b134d8ff92b6478b6559feed9a50bdfd82b3",
}
SRVS = {
    "example_interfaces/srv/AddTwoInts": ("int64 a\nint64 b", "int64 sum"),
    "rcl_interfaces/srv/ListParameters": ("string[] prefixes\nuint64 depth",
                                          "rcl_interfaces/ListParametersResult result"),
    "rcl_interfaces/srv/GetParameters": ("string[] names", "rcl_interfaces/ParameterValue[] values"),
    "rcl_interfaces/srv/SetParameters": ("rcl_interfaces/Parameter[] parameters",
                                         "rcl_interfaces/SetParametersResult[] results"),
    "rcl_interfaces/srv/DescribeParameters": ("string[] names",
                                              "rcl_interfaces/ParameterDescriptor[] descriptors"),
    "rcl_interfaces/srv/GetParameterTypes": ("string[] names", "uint8[] types"),
    "rcl_interfaces/srv/SetParametersAtomically": ("rcl_interfaces/Parameter[] parameters",
                                                   "rcl_interfaces/SetParametersResult result"),
    "action_msgs/srv/CancelGoal": ("action_msgs/GoalInfo goal_info",
                                   "int8 return_code\naction_msgs/GoalInfo[] goals_canceling"),
}
NAV = "nav2_msgs/action/NavigateToPose"
FEEDBACK = ("geometry_msgs/PoseStamped current_pose\nbuiltin_interfaces/Duration navigation_time\n"
            "builtin_interfaces/Duration estimated_time_remaining\nint16 number_of_recoveries\n"
            "float32 distance_remaining")
NAV_PARTS = {"jazzy": ("geometry_msgs/PoseStamped pose\nstring behavior_tree",
                       "uint16 error_code\nstring error_msg", FEEDBACK),
             "humble": ("geometry_msgs/PoseStamped pose\nstring behavior_tree",
                        "std_msgs/Empty result", FEEDBACK)}


def _defs(text: str, name: str) -> dict:
    out = get_types_from_msg(text, name)
    return {k.replace("/srv/msg/", "/srv/"): _rename(v) for k, v in out.items()}


def _rename(x):
    if isinstance(x, str):
        return x.replace("/srv/msg/", "/srv/")
    if isinstance(x, (list, tuple)):
        return type(x)(_rename(i) for i in x)
    return x


def _service(name: str, req: str, resp: str) -> dict:
    out = {**_defs(req, name + "_Request"), **_defs(resp, name + "_Response")}
    out.update(_defs(f"service_msgs/ServiceEventInfo info\n{name}_Request[<=1] request\n"
                     f"{name}_Response[<=1] response", name + "_Event"))
    out.update(_defs(f"{name}_Request request_message\n{name}_Response response_message\n"
                     f"{name}_Event event_message", name))
    return out


def store(distro: str = "jazzy"):
    """A rosbags store of ``distro`` with the services and NavigateToPose added."""
    s = get_typestore(Stores.ROS2_JAZZY if distro == "jazzy" else Stores.ROS2_HUMBLE)
    types = {}
    for name, (req, resp) in SRVS.items():
        types.update(_service(name, req, resp))
    goal, result, feedback = NAV_PARTS[distro]
    types.update({**_defs(goal, NAV + "_Goal"), **_defs(result, NAV + "_Result"),
                  **_defs(feedback, NAV + "_Feedback")})
    types.update(_defs(f"unique_identifier_msgs/UUID goal_id\n{NAV}_Feedback feedback",
                       NAV + "_FeedbackMessage"))
    types.update(_service(NAV + "_SendGoal", f"unique_identifier_msgs/UUID goal_id\n{NAV}_Goal goal",
                          "bool accepted\nbuiltin_interfaces/Time stamp"))
    types.update(_service(NAV + "_GetResult", "unique_identifier_msgs/UUID goal_id",
                          f"int8 status\n{NAV}_Result result"))
    s.register({k: v for k, v in types.items() if k != "service_msgs/msg/ServiceEventInfo"})
    s.fielddefs["service_msgs/msg/ServiceEventInfo"] = _defs(
        "uint8 event_type\nbuiltin_interfaces/Time stamp\nuint8[16] client_gid\nint64 sequence_number",
        "service_msgs/msg/ServiceEventInfo")["service_msgs/msg/ServiceEventInfo"]
    return s


def dds(typename: str) -> str:
    pkg, kind, name = typename.split("/")
    return f"{pkg}::{kind}::dds_::{name}_"


class Client:
    """Calls services, reads topics, of one ROS domain, as an rmw_zenoh client would."""

    def __init__(self, session: zenoh.Session, domain: int, distro: str = "jazzy"):
        self.session, self.domain, self.distro = session, domain, distro
        self.store = store(distro)
        self.gid = bytes(range(16))
        self.seq = 0

    def hash(self, typename: str) -> str:
        return "TypeHashNotSupported" if self.distro == "humble" else self.store.hash_rihs01(typename)

    def key(self, name: str, typename: str) -> str:
        return f"{self.domain}/{name.strip('/')}/{dds(typename)}/{self.hash(typename)}"

    def msg(self, typename: str, **fields):
        return self.store.types[typename](**fields)

    def call(self, name: str, srv: str, request, timeout: float = 10.0):
        """(response, reply attachment (seq, stamp, gid)) of one call; AssertionError if none."""
        self.seq += 1
        att = z_serialize((Int64(self.seq), Int64(time.time_ns()), self.gid)).to_bytes()
        payload = bytes(self.store.serialize_cdr(request, srv + "_Request"))
        for reply in self.session.get(self.key(name, srv), payload=payload, attachment=att,
                                      target=zenoh.QueryTarget.ALL_COMPLETE, timeout=timeout):
            if reply.ok is not None:
                seq, stamp, gid = z_deserialize(tuple[Int64, Int64, bytes], reply.ok.attachment)
                return (self.store.deserialize_cdr(reply.ok.payload.to_bytes(), srv + "_Response"),
                        (int(seq), int(stamp), gid))
        raise AssertionError(f"no reply from {self.key(name, srv)}")

    def tokens(self) -> list[str]:
        return [str(r.ok.key_expr) for r in self.session.liveliness().get(
            f"@ros2_lv/{self.domain}/**", timeout=3.0) if r.ok]

    def time(self, sec: int = 0):
        return self.msg("builtin_interfaces/msg/Time", sec=sec, nanosec=0)

    def goal_request(self, x: float, y: float, frame: str = "map"):
        """(goal id bytes, NavigateToPose_SendGoal_Request)."""
        gid = uuidlib.uuid4().bytes
        c = self.store.types
        pose = c["geometry_msgs/msg/PoseStamped"](
            header=c["std_msgs/msg/Header"](stamp=self.time(), frame_id=frame),
            pose=c["geometry_msgs/msg/Pose"](
                position=c["geometry_msgs/msg/Point"](x=x, y=y, z=0.0),
                orientation=c["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0)))
        return gid, c[NAV + "_SendGoal_Request"](
            goal_id=self.uuid(gid), goal=c[NAV + "_Goal"](pose=pose, behavior_tree=""))

    def uuid(self, raw: bytes):
        return self.msg("unique_identifier_msgs/msg/UUID", uuid=np.frombuffer(raw, np.uint8).copy())
