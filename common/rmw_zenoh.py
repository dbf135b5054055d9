"""rmw_zenoh's wire format, pure (no session): keys, liveliness tokens, GIDs, attachments.

What ``rmw_zenoh_cpp`` (ROS 2 Jazzy and later) writes, read from its sources
(ros2/rmw_zenoh, ``rmw_zenoh_cpp/src/detail/``); each function and class names the source
it follows. Payloads are CDR as on the bridge (:mod:`common.ros2`). ROS 2 Humble's rmw_zenoh
(its ``humble`` branch, released from 0.1.0) writes the same keys, tokens and attachments
with the constant ``TypeHashNotSupported`` where Jazzy has the RIHS01 hash
(:mod:`common.ros2_interfaces`; docs/ros2.md "Humble"): every function taking ``distro``
follows it. Used by :mod:`common.ros_link`, the ROS 2 face and ``papf node``/``topic`` with
``--ros rmw_zenoh``.
"""

from __future__ import annotations

import os
import re
import struct
from dataclasses import dataclass
from functools import cache

from common.errors import ConfigError, SchemaError

ADMIN_SPACE = "@ros2_lv"
NODE, PUBLISHER, SUBSCRIPTION = "NN", "MP", "MS"
SERVICE, CLIENT = "SS", "SC"       # a service server / client: its token names the service
                                   # and the type without "Request_"/"Response_"
                                   # (rmw_service_data.cpp, ServiceData::make)
GID_SIZE = 16                      # [bytes] RMW_GID_STORAGE_SIZE of rmw_zenoh
ATTACHMENT_SIZE = 8 + 8 + 1 + GID_SIZE
DOMAIN_MAX = 232                   # highest ROS_DOMAIN_ID ROS 2 documents as usable
INFINITE_S, INFINITE_NS = 9223372036, 854775807   # RMW_DURATION_INFINITE as (sec, nsec)
_TYPE_RE = re.compile(r"^([A-Za-z][\w]*)/(msg|srv|action)/([A-Za-z]\w*)$")


class AttachmentError(SchemaError):
    """Bytes that are not an rmw_zenoh attachment."""


# -- names ------------------------------------------------------------------------------------
def dds_type_name(typename: str) -> str:
    """``geometry_msgs/msg/Twist`` -> ``geometry_msgs::msg::dds_::Twist_``."""
    m = _TYPE_RE.match(typename)
    if not m:
        raise ConfigError(f"ROS 2 type {typename!r} is not of the form pkg/msg/Name")
    pkg, kind, name = m.groups()
    return f"{pkg}::{kind}::dds_::{name}_"


def ros_type_name(dds_name: str) -> str:
    """``geometry_msgs::msg::dds_::Twist_`` -> ``geometry_msgs/msg/Twist`` (inverse of the above)."""
    parts = dds_name.split("::")
    if len(parts) != 4 or parts[2] != "dds_" or not parts[3].endswith("_"):
        raise SchemaError(f"{dds_name!r} is not an rmw_zenoh DDS type name (pkg::msg::dds_::Name_)")
    return f"{parts[0]}/{parts[1]}/{parts[3][:-1]}"


@cache
def type_hash(typename: str, distro: str = "jazzy") -> str:
    """The type hash rmw_zenoh writes for a ROS 2 message or service type: RIHS01 (REP-2011)
    on jazzy, ``TypeHashNotSupported`` on humble (:func:`common.ros2_interfaces.type_hash`)."""
    from common.ros2_interfaces import type_hash as hash_of

    return hash_of(typename, distro)


def mangle(name: str) -> str:
    """A ROS name as one key-expression chunk (``/`` -> ``%``, rmw_zenoh's mangling)."""
    return name.replace("/", "%")


def demangle(name: str) -> str:
    """Undo :func:`mangle` (``%`` -> ``/``)."""
    return name.replace("%", "/")


def topic_name(topic: str, namespace: str = "") -> str:
    """Fully qualified ROS topic name: ``cmd_vel`` under namespace ``robot1`` -> ``/robot1/cmd_vel``."""
    parts = [p for p in (namespace.strip("/"), topic.strip("/")) if p]
    return "/" + "/".join(parts)


def topic_key(domain: int, topic: str, typename: str, distro: str = "jazzy") -> str:
    """The Zenoh key rmw_zenoh publishes ``topic`` of ``typename`` on in ``domain``.

    Topic key (``liveliness_utils.cpp``, ``TopicInfo::TopicInfo``):
    ``<domain>/<topic without leading/trailing "/">/<dds type>/<type hash>``, e.g.
    ``0/cmd_vel/geometry_msgs::msg::dds_::Twist_/RIHS01_9c45…``. The DDS type name is the
    type support's ``get_name()`` (``pkg::msg::dds_::Name_``); the hash is REP-2011's
    RIHS01 (sha256 of the type description), computed here by ``rosbags``. A service's key
    has the same form (``rmw_service_data.cpp``: the service name, the service type's DDS
    name ``pkg::srv::dds_::Name_`` and its hash); so has an action's, under
    ``<action>/_action/send_goal`` … (rcl_action ``names.c``).
    """
    return (f"{domain}/{topic.strip('/')}/{dds_type_name(typename)}/"
            f"{type_hash(typename, distro)}")


def check_domain(domain: int) -> int:
    """``domain`` as an int; ConfigError unless 0..DOMAIN_MAX."""
    if not 0 <= int(domain) <= DOMAIN_MAX:
        raise ConfigError(f"ROS domain {domain} is out of range: give 0..{DOMAIN_MAX}")
    return int(domain)


def default_domain(environ=os.environ) -> int:
    """``ROS_DOMAIN_ID`` if set (must be an integer 0..232), else 0."""
    raw = environ.get("ROS_DOMAIN_ID", "").strip()
    if not raw:
        return 0
    try:
        return check_domain(int(raw))
    except ValueError:
        raise ConfigError(f"ROS_DOMAIN_ID={raw!r} is not an integer: unset it or give "
                          f"0..{DOMAIN_MAX}") from None


# -- QoS --------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Qos:
    """An rmw QoS profile (rmw enum values: reliable 1 / best effort 2, transient local 1 /
    volatile 2, keep last 1 / keep all 2, liveliness automatic 1); times in (s, ns).

    QoS in a token (``qos_to_keyexpr``): ``R:D:H,depth:dl_s,dl_ns:ls_s,ls_ns:L,lease_s,lease_ns``
    where a field equal to rmw_zenoh's default (``qos.cpp``: reliable, volatile, keep last
    42, infinite deadline/lifespan/lease, automatic liveliness) is left empty.
    """

    reliability: int = 1
    durability: int = 2
    history: int = 1
    depth: int = 42
    deadline: tuple[int, int] = (INFINITE_S, INFINITE_NS)
    lifespan: tuple[int, int] = (INFINITE_S, INFINITE_NS)
    liveliness: int = 1
    lease: tuple[int, int] = (INFINITE_S, INFINITE_NS)

    def keyexpr(self) -> str:
        """The token's QoS field (``qos_to_keyexpr``): defaults left empty."""
        d = DEFAULT_QOS

        def f(value, default) -> str:
            return "" if value == default else str(value)

        return ":".join([
            f(self.reliability, d.reliability), f(self.durability, d.durability),
            f"{f(self.history, d.history)},{f(self.depth, d.depth)}",
            f"{f(self.deadline[0], d.deadline[0])},{f(self.deadline[1], d.deadline[1])}",
            f"{f(self.lifespan[0], d.lifespan[0])},{f(self.lifespan[1], d.lifespan[1])}",
            f"{f(self.liveliness, d.liveliness)},{f(self.lease[0], d.lease[0])},"
            f"{f(self.lease[1], d.lease[1])}"])

    @classmethod
    def parse(cls, text: str) -> Qos:
        """Inverse of :meth:`keyexpr` (``keyexpr_to_qos``); SchemaError on a malformed field."""
        parts = text.split(":")
        if len(parts) != 6:
            raise SchemaError(f"QoS {text!r}: expected 6 ':'-separated fields")
        comps = [p.split(",") for p in parts]
        if [len(c) for c in comps] != [1, 1, 2, 2, 2, 3]:
            raise SchemaError(f"QoS {text!r}: wrong number of ',' components")
        d = DEFAULT_QOS

        def n(value: str, default: int) -> int:
            if value == "":
                return default
            if not value.isdigit():
                raise SchemaError(f"QoS {text!r}: {value!r} is not a number")
            return int(value)

        return cls(reliability=n(parts[0], d.reliability), durability=n(parts[1], d.durability),
                   history=n(comps[2][0], d.history), depth=n(comps[2][1], d.depth),
                   deadline=(n(comps[3][0], d.deadline[0]), n(comps[3][1], d.deadline[1])),
                   lifespan=(n(comps[4][0], d.lifespan[0]), n(comps[4][1], d.lifespan[1])),
                   liveliness=n(comps[5][0], d.liveliness),
                   lease=(n(comps[5][1], d.lease[0]), n(comps[5][2], d.lease[1])))

    def describe(self) -> str:
        """The QoS in words: ``reliable, volatile, keep last 10``."""
        rel = {1: "reliable", 2: "best effort"}.get(self.reliability, str(self.reliability))
        dur = {1: "transient local", 2: "volatile"}.get(self.durability, str(self.durability))
        hist = f"keep last {self.depth}" if self.history == 1 else "keep all"
        return f"{rel}, {dur}, {hist}"


DEFAULT_QOS = Qos()
RELIABLE_10 = Qos(depth=10)                                # rclcpp's usual "10"
SENSOR_DATA = Qos(reliability=2, depth=5)                  # rmw_qos_profile_sensor_data
LATCHED = Qos(durability=1, depth=1)                       # transient local, e.g. robot_description


# -- liveliness tokens ------------------------------------------------------------------------
@dataclass(frozen=True)
class Entity:
    """One node, publisher or subscription as rmw_zenoh announces it (a liveliness token).

    Liveliness token (``Entity::Entity``):
    ``@ros2_lv/<domain>/<zid>/<node id>/<entity id>/<NN|MP|MS|SS|SC>/<enclave>/<namespace>/
    <node>[/<topic>/<dds type>/<type hash>/<qos>]`` with every "/" inside a name mangled
    to "%" (``mangle_name``), so the root namespace is ``%`` and ``/cmd_vel`` is ``%cmd_vel``.
    """

    domain: int
    zid: str
    node_id: int
    entity_id: int
    kind: str                       # NN, MP, MS, SS, SC
    namespace: str                  # ROS namespace, "/" for the root
    node: str
    enclave: str = "/"
    topic: str | None = None        # fully qualified, "/cmd_vel" (a service's name for SS/SC)
    typename: str | None = None     # "geometry_msgs/msg/Twist"
    hash: str | None = None         # "RIHS01_…"
    qos: Qos | None = None

    def token(self) -> str:
        """The liveliness token key of this entity (rmw_zenoh's ``Entity::liveliness_keyexpr``)."""
        parts = [ADMIN_SPACE, str(self.domain), self.zid, str(self.node_id), str(self.entity_id),
                 self.kind, mangle(self.enclave), mangle(self.namespace), mangle(self.node)]
        if self.kind != NODE:
            parts += [mangle(self.topic), mangle(dds_type_name(self.typename)),
                      mangle(self.hash or type_hash(self.typename)), (self.qos or DEFAULT_QOS).keyexpr()]
        return "/".join(parts)

    @property
    def gid(self) -> bytes:
        """The entity's 16-byte GID (derived from its token)."""
        return gid(self.token())

    @classmethod
    def parse(cls, token: str) -> Entity:
        """A token read from the bus -> Entity (``Entity::make(keyexpr)``); SchemaError if malformed."""
        parts = token.split("/")
        if len(parts) < 9 or parts[0] != ADMIN_SPACE or any(p == "" for p in parts):
            raise SchemaError(f"{token!r} is not an rmw_zenoh liveliness token")
        kind = parts[5]
        if kind not in (NODE, PUBLISHER, SUBSCRIPTION, SERVICE, CLIENT):
            raise SchemaError(f"{token!r}: unknown entity kind {kind!r}")
        if not (parts[1].isdigit() and parts[3].isdigit() and parts[4].isdigit()):
            raise SchemaError(f"{token!r}: domain and ids must be numbers")
        base = dict(domain=int(parts[1]), zid=parts[2], node_id=int(parts[3]),
                    entity_id=int(parts[4]), kind=kind, enclave=demangle(parts[6]),
                    namespace=demangle(parts[7]), node=demangle(parts[8]))
        if kind == NODE:
            return cls(**base)
        if len(parts) != 13:
            raise SchemaError(f"{token!r}: a {kind} token has 13 fields, not {len(parts)}")
        return cls(**base, topic=demangle(parts[9]), typename=ros_type_name(demangle(parts[10])),
                   hash=demangle(parts[11]), qos=Qos.parse(parts[12]))

    @property
    def fq_node(self) -> str:
        """The node's fully qualified name (``/namespace/node``)."""
        return topic_name(self.node, self.namespace)


def gid(token: str) -> bytes:
    """The 16-byte GID rmw_zenoh derives from a liveliness token (XXH3-128, low then high, LE).

    GID (``Entity::Entity``): XXH3-128 of the token string, low 64 bits then high 64 bits,
    little endian (16 bytes).
    """
    import xxhash

    h = xxhash.xxh3_128_intdigest(token.encode())
    return (h & (2**64 - 1)).to_bytes(8, "little") + (h >> 64).to_bytes(8, "little")


def liveliness_subscription(domain: int) -> str:
    """Key expression that matches every token of ``domain`` (``subscription_token``)."""
    return f"{ADMIN_SPACE}/{domain}/**"


# -- attachments ------------------------------------------------------------------------------
@dataclass(frozen=True)
class Attachment:
    """
    Attachment of each sample (``attachment_helpers.cpp``, ``serialize_to_zbytes``): zenoh-ext
    serialization of int64 sequence number (from 1), int64 source timestamp (system time,
    ns), std::array<uint8_t, 16> GID — i.e. ``<q`` ``<q`` then the array as a sequence: its
    LEB128 length (16 -> ``0x10``) and the 16 bytes; 33 bytes in all.
    """
    sequence_number: int       # from 1, per publisher
    source_timestamp: int      # [ns] system time at publication
    gid: bytes                 # 16 bytes, the publisher's

    def encode(self) -> bytes:
        """The 33-byte attachment: int64 sequence, int64 stamp [ns], 0x10 and the GID."""
        if len(self.gid) != GID_SIZE:
            raise ValueError(f"GID of {len(self.gid)} bytes, expected {GID_SIZE}")
        return struct.pack("<qqB", self.sequence_number, self.source_timestamp, GID_SIZE) + self.gid

    @classmethod
    def decode(cls, data: bytes | memoryview | None) -> Attachment:
        """A sample's attachment -> Attachment; AttachmentError unless 33 well-formed bytes."""
        data = bytes(data or b"")
        if len(data) != ATTACHMENT_SIZE or data[16] != GID_SIZE:
            raise AttachmentError(f"attachment of {len(data)} bytes ({data[:20].hex()}…): expected "
                                  f"{ATTACHMENT_SIZE} (int64 seq, int64 stamp, 0x10 + 16-byte GID)")
        seq, stamp = struct.unpack_from("<qq", data)
        return cls(seq, stamp, data[17:])
