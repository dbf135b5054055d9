"""``papf topic pub KEY VALUE``: put a message typed on the command line (like ``ros2 topic pub``).

Our keys take our messages (msgpack, the schema of the key's topic); a ROS 2 topic
(leading ``/``) takes CDR of ``--ros-type`` (or the type the topic has on the ROSbot),
on the bridge's key or, with ``--ros rmw_zenoh``, as the ROS 2 node ``/papf_topic_pub``
with rmw_zenoh's key, tokens and attachments. Fields: :mod:`papf.bus.fields`.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

from common import ros2_convert as rc
from common.errors import ConfigError
from common.ros_link import BridgeLink, RmwZenohLink
from papf.bus.decode import ROS_TYPES
from papf.bus.fields import our_message, ros_message
from schemas import Keys
from schemas.keys import TOPICS

ROS_NODE = "papf_topic_pub"


class Prepared:
    """What to put where: a publisher factory and the payload, resolved before any session."""

    def __init__(self, key_name: str, payload: bytes, typename: str, ros_topic: str | None):
        self.key_name, self.payload, self.typename, self.ros_topic = (key_name, payload, typename,
                                                                      ros_topic)


def prepare(name: str, value: dict, keys: Keys, ros_type: str | None = None) -> Prepared:
    """Check KEY and VALUE and encode the message (ConfigError: what was wrong, what is valid)."""
    if name in TOPICS:
        msg = our_message(TOPICS[name], value)
        return Prepared(keys.key(name), msg.to_bytes(), msg.TYPE, None)
    if name.startswith("/"):
        topic = name.strip("/")
        typename = ros_type or ROS_TYPES.get(topic)
        if typename is None:
            raise ConfigError(f"{name}: give its type with --ros-type (e.g. "
                              "geometry_msgs/msg/Twist); known topics: "
                              f"{', '.join('/' + t for t in ROS_TYPES)}")
        msg = ros_message(rc.typestore(), typename, value)
        return Prepared(topic, rc.serialize(msg, typename), typename, topic)
    raise ConfigError(f"KEY {name!r}: give a stack topic ({', '.join(sorted(TOPICS))}) or a "
                      "ROS 2 topic with a leading / (/cmd_vel)")


def publish(session, p: Prepared, ros: str, domain: int, times: int, rate_hz: float,
            out: Callable[[str], None], stop: Callable[[], bool], duration_s: float = 0.0,
            distro: str = "jazzy") -> int:
    """Put ``p`` ``times`` times (0: until stopped) at ``rate_hz``, for at most ``duration_s``
    (0: no limit); returns how many went out."""
    link = None
    if p.ros_topic is None:
        pub, key = session.declare_publisher(p.key_name), p.key_name
    else:
        link = (RmwZenohLink(session, domain, ROS_NODE, distro=distro) if ros == "rmw_zenoh"
                else BridgeLink(session))
        pub, key = link.publisher(p.ros_topic, p.typename), link.key(p.ros_topic, p.typename)
    out(f"publishing {p.typename} on {key}" + (f" at {rate_hz:g} Hz" if times != 1 else ""))
    sent = 0
    try:
        time.sleep(0.3)        # let the subscribers' interest reach us before the first put
        end = time.monotonic() + duration_s if duration_s > 0 else math.inf
        while not stop() and (times <= 0 or sent < times) and time.monotonic() < end:
            pub.put(p.payload)
            sent += 1
            if times <= 0 or sent < times:
                time.sleep(min(1.0 / rate_hz, max(end - time.monotonic(), 0.0)))
        time.sleep(0.2)        # flush before the session closes
    finally:
        if link is not None:
            link.close()
        else:
            pub.undeclare()
    return sent
