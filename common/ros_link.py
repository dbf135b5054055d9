"""The robot's ROS 2 middleware on a Zenoh session: the bridge or rmw_zenoh (thin, no maths).

``--ros bridge`` (default, ``zenoh-bridge-ros2dds``) or ``--ros rmw_zenoh`` (we are ROS 2
nodes, :mod:`common.rmw_zenoh`). :func:`open_link` gives a :class:`RosLink` that hands
out publishers and subscriptions by ROS topic and type; :class:`BridgeTopics` names the
robot's own topics on it. Used by the base driver, the real LiDAR source
(``nodes/lidar_sim/ros2_source.py``), the ROS 2 face and ``papf rosbot-emulator``.
"""

from __future__ import annotations

import argparse
import itertools
import threading
import time
from dataclasses import dataclass

from common import rmw_zenoh as rz
from common.errors import ConfigError, SchemaError
from common.ros2_interfaces import DEFAULT_DISTRO, DISTROS, check_distro

MIDDLEWARES = ("bridge", "rmw_zenoh")
CMD_VEL_TYPES = {"twist": "geometry_msgs/msg/Twist",
                 "twist_stamped": "geometry_msgs/msg/TwistStamped"}


@dataclass(frozen=True)
class BridgeTopics:
    """Bridge keys of the robot's ROS 2 topics: ``[<namespace>/]<topic>``.

    The bridge namespace is a setting of its own, distinct from our key namespace:
    :meth:`check_separate` refuses any overlap with our msgpack keys (docs/architecture.md "The robot").
    """

    namespace: str = ""
    cmd_vel: str = "cmd_vel"
    odometry: str = "odometry/filtered"
    battery: str = "battery"
    scan: str = "scan"

    def key(self, topic: str) -> str:
        topic = topic.strip("/")
        return f"{self.namespace.strip('/')}/{topic}" if self.namespace.strip("/") else topic

    @property
    def keys(self) -> dict[str, str]:
        return {t: self.key(getattr(self, t)) for t in ("cmd_vel", "odometry", "battery", "scan")}

    def check_separate(self, our_namespace: str) -> None:
        """ConfigError if a bridge key falls under ``<our_namespace>/`` (or contains wildcards)."""
        for name, key in self.keys.items():
            if not key or "*" in key or "$" in key:
                raise ConfigError(f"bridge {name} key {key!r} must be a plain key without wildcards")
            if key == our_namespace or key.startswith(our_namespace + "/"):
                raise ConfigError(
                    f"bridge {name} key {key!r} overlaps our namespace {our_namespace!r}: the "
                    "bridge carries CDR and our keys msgpack; give the bridge another namespace "
                    "(--bridge-namespace) or none")


def add_ros_args(parser: argparse.ArgumentParser, cmd_vel: bool = True) -> None:
    """``--ros``, ``--ros-domain``, ``--ros-distro`` (and ``--cmd-vel-type``) on a node or command."""
    g = parser.add_argument_group("the robot's ROS 2 middleware")
    g.add_argument("--ros", choices=MIDDLEWARES, default="bridge",
                   help="zenoh-bridge-ros2dds (default) or rmw_zenoh (ROS 2 Humble or Jazzy and later)")
    g.add_argument("--ros-domain", type=int, default=None, metavar="N",
                   help="ROS domain id for rmw_zenoh (default: $ROS_DOMAIN_ID, else 0)")
    add_distro_arg(g)
    if cmd_vel:
        g.add_argument("--cmd-vel-type", choices=tuple(CMD_VEL_TYPES), default="twist",
                       help="cmd_vel message: twist (the ROSbot's default) or twist_stamped")


def add_distro_arg(parser) -> None:
    """``--ros-distro jazzy|humble``: which rmw_zenoh's keys (type hashes) and message
    definitions to speak (docs/ros2.md "Humble")."""
    parser.add_argument("--ros-distro", choices=DISTROS, default=DEFAULT_DISTRO,
                        help="the ROS 2 distro on rmw_zenoh: jazzy (and later: RIHS01 type "
                             "hashes, default) or humble (rmw_zenoh 0.1: no type hashes)")


def ros_distro(args: argparse.Namespace) -> str:
    """``--ros-distro`` checked (ConfigError on an unknown one)."""
    return check_distro(getattr(args, "ros_distro", DEFAULT_DISTRO) or DEFAULT_DISTRO)


def add_face_args(parser: argparse.ArgumentParser) -> None:
    """``--ros-face [--ros-face-domain N]`` of ``papf run`` and ``papf launch``."""
    parser.add_argument("--ros-face", action="store_true",
                        help="also show the stack to ROS 2 tools and RViz over rmw_zenoh "
                             "(nodes.ros_face; docs/robot.md \"The ROS 2 face\")")
    parser.add_argument("--ros-face-domain", type=int, default=None, metavar="N",
                        help="ROS domain of the face (default: $ROS_DOMAIN_ID, else 0); must "
                             "differ from a robot's on rmw_zenoh")
    parser.add_argument("--ros-face-distro", choices=DISTROS, default=DEFAULT_DISTRO,
                        help="the face's ROS 2 distro: jazzy (default; and later) or humble "
                             "(rmw_zenoh 0.1: no type hashes)")


def face_domain(args: argparse.Namespace) -> int | None:
    """The face's domain when ``--ros-face`` is on (None when off); ConfigError if it is the
    domain of the robot's rmw_zenoh (``--ros rmw_zenoh``): its /cmd_vel would bypass the driver."""
    if not getattr(args, "ros_face", False):
        return None
    value = getattr(args, "ros_face_domain", None)
    domain = rz.default_domain() if value is None else rz.check_domain(value)
    if getattr(args, "ros", "bridge") == "rmw_zenoh" and domain == ros_domain(args):
        raise ConfigError(f"--ros-face in ROS domain {domain}, the robot's rmw_zenoh domain: the "
                          "face's /cmd_vel, /scan and /odom would mix with the robot's; give "
                          "--ros-face-domain another domain")
    return domain


def face_distro(args: argparse.Namespace) -> str:
    """``--ros-face-distro`` checked (ConfigError on an unknown one)."""
    return check_distro(getattr(args, "ros_face_distro", DEFAULT_DISTRO) or DEFAULT_DISTRO)


def ros_domain(args: argparse.Namespace) -> int:
    """``--ros-domain`` checked, else ``ROS_DOMAIN_ID``, else 0 (ConfigError on a bad value)."""
    value = getattr(args, "ros_domain", None)
    return rz.default_domain() if value is None else rz.check_domain(value)


def cmd_vel_type(args: argparse.Namespace) -> str:
    """The ROS type name of cmd_vel chosen by ``--cmd-vel-type``; ConfigError if unknown."""
    name = getattr(args, "cmd_vel_type", "twist")
    if name not in CMD_VEL_TYPES:
        raise ConfigError(f"--cmd-vel-type {name!r}: give one of {', '.join(CMD_VEL_TYPES)}")
    return CMD_VEL_TYPES[name]


class RosLink:
    """Common part: remember what was declared, undeclare it on :meth:`close`.

    ``--ros bridge`` (default): ``zenoh-bridge-ros2dds`` maps ROS topic ``/t`` to key
    ``[<ns>/]t``; we put and take bare CDR. ``--ros rmw_zenoh``: we are ROS 2 nodes on
    rmw_zenoh's own wire format (:mod:`common.rmw_zenoh`): the key with domain, DDS type name
    and RIHS01 hash, a liveliness token for our node and for each publisher and subscription
    (so ``ros2 node list`` / ``ros2 topic info -v`` on the robot see us) and each sample's
    attachment (sequence number, source timestamp, GID).

    A link hands out publishers (``put(cdr)``) and subscriptions (callback with the CDR
    bytes) by ROS topic and type; :meth:`RosLink.close` undeclares all of it.

    ``--cmd-vel-type twist|twist_stamped``: Jazzy's diff-drive controller can take
    ``geometry_msgs/TwistStamped``; the ROSbot's default stays ``Twist``.
    """

    middleware = ""

    def __init__(self, session, namespace: str = ""):
        self.session, self.namespace = session, namespace.strip("/")
        self._declared: list = []

    def key(self, topic: str, typename: str) -> str:
        """The Zenoh key of ROS ``topic`` of type ``typename`` (each link's own mapping)."""
        raise NotImplementedError

    def close(self) -> None:
        """Undeclare every publisher, subscriber and token, newest first."""
        for thing in reversed(self._declared):
            try:
                thing.undeclare()
            except Exception:  # noqa: BLE001 - a closed session: nothing left to undeclare
                pass
        self._declared.clear()

    def _keep(self, thing):
        self._declared.append(thing)
        return thing


class BridgeLink(RosLink):
    """zenoh-bridge-ros2dds: topic ``t`` -> key ``[<ns>/]t``, bare CDR."""

    middleware = "bridge"

    def key(self, topic: str, typename: str = "") -> str:
        """The bridge's key of ``topic``: under the bridge's namespace (no type in it)."""
        topic = topic.strip("/")
        return f"{self.namespace}/{topic}" if self.namespace else topic

    def publisher(self, topic: str, typename: str, qos: rz.Qos = rz.RELIABLE_10):
        """A publisher of ``topic`` (plain CDR; ``typename`` and ``qos`` unused)."""
        return self._keep(self.session.declare_publisher(self.key(topic)))

    def subscribe(self, topic: str, typename: str, callback, qos: rz.Qos = rz.RELIABLE_10):
        """Call ``callback(cdr_bytes)`` for each message on ``topic``."""
        return self._keep(self.session.declare_subscriber(
            self.key(topic), lambda s: callback(s.payload.to_bytes())))


class _RmwPublisher:
    """A publisher with rmw_zenoh's attachment on every sample (sequence numbers from 1)."""

    def __init__(self, zpub, gid: bytes):
        self.zpub, self.gid = zpub, gid
        self.seq = itertools.count(1)
        self._lock = threading.Lock()

    def put(self, cdr: bytes) -> None:
        with self._lock:
            att = rz.Attachment(next(self.seq), time.time_ns(), self.gid).encode()
            self.zpub.put(cdr, attachment=att)

    def undeclare(self) -> None:
        self.zpub.undeclare()


class _RmwService:
    """A service server the rmw_zenoh way (``rmw_service_data.cpp``): a complete queryable on
    the service's key; each query carries the request's CDR and the client's attachment
    (sequence number, stamp, client GID); the reply goes on the service's key with the CDR
    response and an attachment of the request's sequence number, our stamp and the
    client's GID, which is how the client matches it (``rmw_client_data.cpp``)."""

    def __init__(self, session, key: str, handler, log=None):
        self.key, self.handler, self.log = key, handler, log
        self.bad = 0
        self.queryable = session.declare_queryable(key, self._on_query, complete=True)

    def _on_query(self, query) -> None:
        try:
            att = rz.Attachment.decode(query.attachment.to_bytes() if query.attachment else b"")
        except SchemaError as exc:   # not an rmw_zenoh client: counted and dropped
            self.bad += 1
            if self.log is not None and self.bad <= 5:
                self.log.warning("dropped a request on %s: %s", self.key, exc)
            return
        payload = query.payload.to_bytes() if query.payload is not None else b""
        self.handler(payload, Reply(query, self.key, att))

    def undeclare(self) -> None:
        self.queryable.undeclare()


class Reply:
    """How to answer one service request, now or later (a query kept until its goal ends)."""

    def __init__(self, query, key: str, request: rz.Attachment):
        self.query, self.key, self.request = query, key, request
        self.sent = False

    def send(self, cdr: bytes) -> None:
        """Reply once with ``cdr`` (a second call does nothing)."""
        if self.sent:
            return
        self.sent = True
        att = rz.Attachment(self.request.sequence_number, time.time_ns(), self.request.gid)
        try:
            self.query.reply(self.key, cdr, attachment=att.encode())
        finally:
            self.query.drop()   # the reply is final: the client's get completes


class RmwZenohLink(RosLink):
    """One ROS 2 node on rmw_zenoh: ``/<ns>/<node>`` in ``domain``, its node token declared now."""

    middleware = "rmw_zenoh"

    def __init__(self, session, domain: int, node: str, namespace: str = "",
                 ids: itertools.count | None = None, distro: str = DEFAULT_DISTRO, log=None):
        """``ids``: entity ids shared by every link on one session (several ROS nodes);
        ``distro``: whose type hashes go in keys and tokens (``humble``: none)."""
        super().__init__(session, namespace)
        self.distro, self.log = check_distro(distro), log
        self.domain = rz.check_domain(domain)
        self.zid = str(session.info.zid())
        self.ids = ids or itertools.count(0)
        node_id = next(self.ids)
        self.node_entity = rz.Entity(self.domain, self.zid, node_id, node_id, rz.NODE,
                                     "/" + self.namespace if self.namespace else "/", node)
        self._token(self.node_entity)

    def key(self, topic: str, typename: str) -> str:
        """The rmw_zenoh key of ``topic`` of ``typename`` in this domain and namespace."""
        return rz.topic_key(self.domain, self._fq(topic), typename, self.distro)

    def _fq(self, name: str) -> str:
        """A name under the link's namespace; one with a leading "/" is absolute."""
        return name if name.startswith("/") else rz.topic_name(name, self.namespace)

    def _entity(self, kind: str, topic: str, typename: str, qos: rz.Qos) -> rz.Entity:
        n = self.node_entity
        return rz.Entity(self.domain, self.zid, n.node_id, next(self.ids), kind, n.namespace,
                         n.node, topic=self._fq(topic), typename=typename,
                         hash=rz.type_hash(typename, self.distro), qos=qos)

    def _token(self, entity: rz.Entity):
        return self._keep(self.session.liveliness().declare_token(entity.token()))

    def publisher(self, topic: str, typename: str, qos: rz.Qos = rz.RELIABLE_10) -> _RmwPublisher:
        """A publisher; transient local QoS keeps the last ``depth`` samples for late joiners
        as rmw_zenoh does (``rmw_publisher_data.cpp``: zenoh-ext advanced publisher with a
        cache and publisher detection, sample-miss heartbeats when reliable)."""
        entity = self._entity(rz.PUBLISHER, topic, typename, qos)
        key = self.key(topic, typename)
        if qos.durability == 1:
            from zenoh import ext

            miss = ext.MissDetectionConfig(sporadic_heartbeat=0.5) if qos.reliability == 1 else None
            zpub = ext.declare_advanced_publisher(
                self.session, key, cache=ext.CacheConfig(max_samples=qos.depth),
                sample_miss_detection=miss, publisher_detection=True)
        elif qos.reliability == 2:   # best effort: dropped rather than queued under congestion
            import zenoh

            zpub = self.session.declare_publisher(
                key, reliability=zenoh.Reliability.BEST_EFFORT,
                congestion_control=zenoh.CongestionControl.DROP)
        else:
            zpub = self.session.declare_publisher(key)
        pub = self._keep(_RmwPublisher(zpub, entity.gid))
        self._token(entity)
        return pub

    def subscribe(self, topic: str, typename: str, callback, qos: rz.Qos = rz.RELIABLE_10):
        """Deliver each sample's CDR bytes to ``callback`` (the attachment is not needed to decode)."""
        entity = self._entity(rz.SUBSCRIPTION, topic, typename, qos)
        sub = self._keep(self.session.declare_subscriber(
            self.key(topic, typename), lambda s: callback(s.payload.to_bytes())))
        self._token(entity)
        return sub


    def service(self, name: str, typename: str, handler, qos: rz.Qos = rz.RELIABLE_10):
        """Serve ROS service ``name`` (relative to the link's namespace, or absolute with a
        leading "/") of ``typename`` (``pkg/srv/Name``): ``handler(request_cdr, reply)`` is
        called on Zenoh's thread; ``reply.send(response_cdr)`` answers, at once or later."""
        entity = self._entity(rz.SERVICE, name, typename, qos)
        srv = self._keep(_RmwService(self.session, self.key(name, typename), handler, self.log))
        self._token(entity)
        return srv


def open_link(args: argparse.Namespace, session, node: str, namespace: str = "") -> RosLink:
    """The link ``--ros`` asks for; ``node`` names our ROS 2 node on rmw_zenoh."""
    middleware = getattr(args, "ros", "bridge")
    if middleware == "bridge":
        return BridgeLink(session, namespace)
    if middleware == "rmw_zenoh":
        return RmwZenohLink(session, ros_domain(args), node, namespace,
                            distro=ros_distro(args))
    raise ConfigError(f"--ros {middleware!r}: give one of {', '.join(MIDDLEWARES)}")
