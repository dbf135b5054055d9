"""Nav2's ``navigate_to_pose`` action on our planner, pure: goals, statuses, feedback, results.

:class:`Navigator` is the action server's state (no transport): the face feeds it the
action's requests (CDR, :mod:`common.ros2_interfaces`) and our planner's messages, and
publishes what it returns. The action's wire is rcl_action's (``names.c``): the services
``<action>/_action/send_goal``, ``cancel_goal``, ``get_result`` and the topics
``<action>/_action/feedback``, ``<action>/_action/status`` (transient local, depth 1:
``rcl_action_qos_profile_status_default``).

How a Nav2 goal becomes ours: an accepted goal is published as our :class:`~schemas.Goal`
(the face signs it, as ``papf goal`` would); the planner answers ``ready`` then drives.
Goal statuses (action_msgs/GoalStatus): ACCEPTED until the planner acknowledges, then
EXECUTING; SUCCEEDED when the planner reports ``reached``; ABORTED when it reports
``stagnated``/``failed`` or when a newer goal preempts it (nav2's SimpleActionServer
aborts the preempted goal too); a cancel publishes a cancelling goal (the planner drops its
goal and commands zero speed) and the goal is CANCELED once the planner reports ``idle``.
The goal's orientation and ``behavior_tree`` are not used: our planners drive to a point
(a goal naming a behaviour tree is taken, with a log line).
"""

from __future__ import annotations

import dataclasses
import math
from collections import OrderedDict

import numpy as np

from common import ros2_interfaces as ri
from common.errors import SchemaError
from common.units import NS_PER_S
from schemas import Goal, Odometry, PlannerState, PlannerStatus

ACTION = ri.NAVIGATE_TO_POSE
A = ACTION                        # type names below: f"{A}_SendGoal" …
UNKNOWN, ACCEPTED, EXECUTING, CANCELING, SUCCEEDED, CANCELED, ABORTED = range(7)
TERMINAL = (SUCCEEDED, CANCELED, ABORTED)
CANCEL_OK, CANCEL_REJECTED, CANCEL_UNKNOWN, CANCEL_TERMINATED = range(4)
GOAL_FRAMES = ("map", "odom", "")   # map -> odom is the identity in our stack
GOALS_KEPT = 10                      # [-] goals listed in the status array (newest)
FEEDBACK_PERIOD_NS = 200_000_000     # [ns] feedback at most every 0.2 s of run time (5 Hz)
ERROR_UNKNOWN = 9000                 # nav2_msgs NavigateToPose.action (kilted): UNKNOWN
ESCAPE_MODES = ("drive", "stop", "idle", "stale")   # a switch to any other mode: a recovery


@dataclasses.dataclass
class _Entry:
    uuid: bytes
    x: float
    y: float
    frame: str
    stamp_ns: int                    # when accepted (run time)
    status: int = ACCEPTED
    error_code: int = 0
    error_msg: str = ""
    recoveries: int = 0
    waiting: list = dataclasses.field(default_factory=list)   # get_result replies held


class Navigator:
    """The action server's goals. Methods return what to publish or reply; nothing is sent here.

    ``accept``: take goals (``papf launch``, realtime runs) or refuse them all (a lockstep
    ``papf run`` keeps its world's goal: runs stay deterministic).
    """

    def __init__(self, distro: str = ri.DEFAULT_DISTRO, accept: bool = True, log=None):
        self.distro, self.accept, self.log = distro, accept, log
        self.goals: OrderedDict[bytes, _Entry] = OrderedDict()
        self.active: _Entry | None = None
        self.started = False             # the planner acknowledged the active goal
        self.canceling: _Entry | None = None
        self.cancel_ns = 0
        self.odom: Odometry | None = None
        self.last_feedback_ns = -FEEDBACK_PERIOD_NS
        self.last_mode = "drive"
        self.now_ns = 0
        self.template: Goal | None = None    # the run's goal: tolerance and road kept
        self.rejected = 0

    # -- requests -------------------------------------------------------------------------------
    def send_goal(self, data: bytes) -> tuple[bytes, Goal | None, list]:
        """A ``send_goal`` request -> (response CDR, our goal to publish or None, replies to
        send: (reply, CDR) of goals it preempts)."""
        req = self._decode(data, f"{A}_SendGoal_Request")
        uuid = bytes(np.asarray(req.goal_id.uuid, dtype=np.uint8))
        pose = req.goal.pose
        why = self._refusal(uuid, pose)
        if why:
            self.rejected += 1
            if self.log is not None:
                self.log.warning("navigate_to_pose goal refused: %s", why)
            return self._send_goal_response(False), None, []
        x, y = float(pose.pose.position.x), float(pose.pose.position.y)
        if req.goal.behavior_tree and self.log is not None:
            self.log.info("navigate_to_pose: behavior_tree %r not used (PAPF drives to the "
                          "point)", req.goal.behavior_tree[:80])
        replies = self._finish(self.active, ABORTED, ERROR_UNKNOWN, "preempted by a new goal")
        entry = _Entry(uuid, x, y, pose.header.frame_id or "odom", self.now_ns)
        self._remember(entry)
        self.active, self.started, self.canceling = entry, False, None
        self.last_feedback_ns, self.last_mode = -FEEDBACK_PERIOD_NS, "drive"
        return self._send_goal_response(True), self._our_goal(x, y), replies

    def cancel_goal(self, data: bytes) -> tuple[bytes, Goal | None]:
        """A ``cancel_goal`` request -> (response CDR, the cancelling goal to publish or None).

        action_msgs/CancelGoal: a zero id and zero stamp cancel every goal; a zero id and a
        stamp, the goals accepted at or before it; an id, that goal (and those before the
        stamp, if one is given)."""
        req = self._decode(data, f"{ri.CANCEL_GOAL}_Request")
        uuid = bytes(np.asarray(req.goal_info.goal_id.uuid, dtype=np.uint8))
        stamp = int(req.goal_info.stamp.sec) * NS_PER_S + int(req.goal_info.stamp.nanosec)
        chosen = [e for e in self.goals.values() if _cancel_matches(e, uuid, stamp)]
        if not self.accept:
            return self._cancel_response(CANCEL_REJECTED, []), None
        if uuid != bytes(16) and uuid not in self.goals:
            return self._cancel_response(CANCEL_UNKNOWN, []), None
        live = [e for e in chosen if e.status not in TERMINAL]
        if not live:
            return self._cancel_response(CANCEL_TERMINATED if chosen else CANCEL_OK, []), None
        for e in live:
            e.status = CANCELING
        stop = None
        if self.active in live:
            self.canceling, self.cancel_ns = self.active, self.now_ns
            stop = dataclasses.replace(self._our_goal(self.active.x, self.active.y), cancel=True)
        return self._cancel_response(CANCEL_OK, live), stop

    def get_result(self, data: bytes, reply) -> list:
        """A ``get_result`` request: [(reply, CDR)] now if the goal ended (or is unknown),
        else the reply is held until it ends."""
        req = self._decode(data, f"{A}_GetResult_Request")
        entry = self.goals.get(bytes(np.asarray(req.goal_id.uuid, dtype=np.uint8)))
        if entry is None:
            return [(reply, self._result(UNKNOWN, 0, "unknown goal"))]
        if entry.status in TERMINAL:
            return [(reply, self._result(entry.status, entry.error_code, entry.error_msg))]
        entry.waiting.append(reply)
        return []

    # -- our messages ---------------------------------------------------------------------------
    def on_goal(self, goal: Goal) -> None:
        """The run's goal (tolerance and road are kept for Nav2's goals)."""
        if not getattr(goal, "cancel", False):
            self.template = goal

    def on_status(self, status: PlannerStatus) -> list:
        """The planner's status -> [(reply, CDR)] of get_result requests now answered."""
        self.now_ns = max(self.now_ns, status.stamp_ns)
        if self.canceling is not None and status.state == "idle" \
                and status.stamp_ns >= self.cancel_ns:
            entry, self.canceling = self.canceling, None
            if entry is self.active:
                self.active = None
            return self._finish(entry, CANCELED, 0, "")
        e = self.active
        if e is None or e.status == CANCELING:
            return []
        if status.state in ("ready", "driving") and status.stamp_ns >= e.stamp_ns:
            self.started, e.status = True, EXECUTING
        elif self.started and status.state == "reached":
            self.active = None
            return self._finish(e, SUCCEEDED, 0, "")
        elif self.started and status.state in ("stagnated", "failed"):
            self.active = None
            return self._finish(e, ABORTED, ERROR_UNKNOWN, f"{status.state}: {status.reason}")
        return []

    def on_state(self, state: PlannerState) -> None:
        """Count the planner's escapes from its plain drive (Nav2's "recoveries")."""
        if self.active is not None and state.mode != self.last_mode:
            if self.last_mode in ESCAPE_MODES and state.mode not in ESCAPE_MODES:
                self.active.recoveries += 1
            self.last_mode = state.mode

    def on_odom(self, odom: Odometry) -> bytes | None:
        """The robot's pose -> a feedback message (CDR) at most every 0.2 s of run time."""
        self.odom, self.now_ns = odom, max(self.now_ns, odom.stamp_ns)
        e = self.active
        if e is None or e.status != EXECUTING or \
                odom.stamp_ns - self.last_feedback_ns < FEEDBACK_PERIOD_NS:
            return None
        self.last_feedback_ns = odom.stamp_ns
        return self._feedback(e, odom)

    def status_array(self) -> bytes:
        """action_msgs/GoalStatusArray of the goals kept (newest last)."""
        c = ri.typestore(self.distro).types
        out = [c["action_msgs/msg/GoalStatus"](goal_info=self._goal_info(e), status=e.status)
               for e in self.goals.values()]
        return ri.serialize(c["action_msgs/msg/GoalStatusArray"](status_list=out),
                            "action_msgs/msg/GoalStatusArray", self.distro)

    # -- helpers --------------------------------------------------------------------------------
    def _decode(self, data: bytes, typename: str):
        try:
            return ri.deserialize(data, typename, self.distro)
        except Exception as exc:   # rosbags raises struct/index errors on garbage
            raise SchemaError(f"{typename}: {len(data)} bytes are not its CDR "
                              f"({type(exc).__name__})") from None

    def _refusal(self, uuid: bytes, pose) -> str:
        if not self.accept:
            return "this lockstep run keeps its world's goal (runs stay deterministic); use " \
                   "papf launch or papf run --realtime"
        if uuid in self.goals:
            return "a goal with this id was already sent"
        if pose.header.frame_id not in GOAL_FRAMES:
            return f"frame {pose.header.frame_id!r}: give 'map' or 'odom' (the run's world frame)"
        x, y = float(pose.pose.position.x), float(pose.pose.position.y)
        if not (math.isfinite(x) and math.isfinite(y)):
            return f"position ({x!r}, {y!r}) is not finite"
        return ""

    def _our_goal(self, x: float, y: float) -> Goal:
        if self.template is not None:
            return dataclasses.replace(self.template, stamp_ns=self.now_ns, x=x, y=y, auth="")
        return Goal(stamp_ns=self.now_ns, x=x, y=y)

    def _remember(self, entry: _Entry) -> None:
        self.goals[entry.uuid] = entry
        while len(self.goals) > GOALS_KEPT:
            old = next(e for e in self.goals.values())
            if old.status not in TERMINAL:
                break
            self.goals.popitem(last=False)

    def _finish(self, entry: _Entry | None, status: int, code: int, msg: str) -> list:
        if entry is None or entry.status in TERMINAL:
            return []
        entry.status, entry.error_code, entry.error_msg = status, code, msg
        if self.log is not None:
            self.log.info("navigate_to_pose goal (%.2f, %.2f): %s%s", entry.x, entry.y,
                          ("", "", "", "", "succeeded", "canceled", "aborted")[status],
                          f" ({msg})" if msg else "")
        out = [(r, self._result(status, code, msg)) for r in entry.waiting]
        entry.waiting.clear()
        return out

    def _time(self, ns: int):
        return ri.msg_class("builtin_interfaces/msg/Time", self.distro)(
            sec=int(ns) // NS_PER_S, nanosec=int(ns) % NS_PER_S)

    def _duration(self, seconds: float):
        ns = max(0, round(seconds * NS_PER_S))
        return ri.msg_class("builtin_interfaces/msg/Duration", self.distro)(
            sec=min(ns // NS_PER_S, 2**31 - 1), nanosec=ns % NS_PER_S)

    def _goal_info(self, e: _Entry):
        c = ri.typestore(self.distro).types
        return c["action_msgs/msg/GoalInfo"](
            goal_id=c["unique_identifier_msgs/msg/UUID"](uuid=np.frombuffer(e.uuid, np.uint8)),
            stamp=self._time(e.stamp_ns))

    def _send_goal_response(self, accepted: bool) -> bytes:
        cls = ri.msg_class(f"{A}_SendGoal_Response", self.distro)
        return ri.serialize(cls(accepted=accepted, stamp=self._time(self.now_ns)),
                            f"{A}_SendGoal_Response", self.distro)

    def _cancel_response(self, code: int, goals: list) -> bytes:
        name = f"{ri.CANCEL_GOAL}_Response"
        cls = ri.msg_class(name, self.distro)
        return ri.serialize(cls(return_code=code, goals_canceling=[self._goal_info(e) for e in goals]),
                            name, self.distro)

    def _result(self, status: int, code: int, msg: str) -> bytes:
        c = ri.typestore(self.distro).types
        if self.distro == "humble":   # std_msgs/Empty result
            result = c[f"{A}_Result"](result=c["std_msgs/msg/Empty"](
                structure_needs_at_least_one_member=0))
        else:
            result = c[f"{A}_Result"](error_code=code, error_msg=msg)
        return ri.serialize(c[f"{A}_GetResult_Response"](status=status, result=result),
                            f"{A}_GetResult_Response", self.distro)

    def _feedback(self, e: _Entry, odom: Odometry) -> bytes:
        c = ri.typestore(self.distro).types
        dist = math.hypot(e.x - odom.x, e.y - odom.y)
        eta = dist / abs(odom.v) if abs(odom.v) > 0.01 else 0.0
        pose = c["geometry_msgs/msg/PoseStamped"](
            header=c["std_msgs/msg/Header"](stamp=self._time(odom.stamp_ns), frame_id=e.frame),
            pose=c["geometry_msgs/msg/Pose"](
                position=c["geometry_msgs/msg/Point"](x=odom.x, y=odom.y, z=0.0),
                orientation=c["geometry_msgs/msg/Quaternion"](
                    x=0.0, y=0.0, z=math.sin(odom.yaw / 2), w=math.cos(odom.yaw / 2))))
        fb = c[f"{A}_Feedback"](
            current_pose=pose, navigation_time=self._duration((odom.stamp_ns - e.stamp_ns) / NS_PER_S),
            estimated_time_remaining=self._duration(eta), number_of_recoveries=min(e.recoveries, 32767),
            distance_remaining=float(dist))
        msg = c[f"{A}_FeedbackMessage"](
            goal_id=c["unique_identifier_msgs/msg/UUID"](uuid=np.frombuffer(e.uuid, np.uint8)),
            feedback=fb)
        return ri.serialize(msg, f"{A}_FeedbackMessage", self.distro)


def _cancel_matches(e: _Entry, uuid: bytes, stamp_ns: int) -> bool:
    """action_msgs/CancelGoal's rules for one goal."""
    if uuid == bytes(16):
        return stamp_ns == 0 or e.stamp_ns <= stamp_ns
    return e.uuid == uuid or (stamp_ns != 0 and e.stamp_ns <= stamp_ns)
