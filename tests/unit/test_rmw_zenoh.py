"""rmw_zenoh's wire format (common/rmw_zenoh.py) against values that are not ours.

Sources of the expected values (never our own encoder):
- ros2/rmw_zenoh @3411fde ``rmw_zenoh_cpp/src/detail/liveliness_utils.cpp``:
  ``TopicInfo::TopicInfo`` (key = domain/strip_slashes(name)/type/hash),
  ``Entity::Entity`` (token fields, ``mangle_name``, GID = XXH3-128 low64|high64),
  ``qos_to_keyexpr`` (defaults left empty); ``qos.cpp`` @7efeee2 (defaults: reliable,
  volatile, keep last 42, infinite times, automatic liveliness).
- ros2/rmw_zenoh @534747d ``attachment_helpers.cpp`` lines 67-74 (``serialize_to_zbytes``:
  int64 sequence number, int64 source timestamp, std::array<uint8_t, 16> GID through
  zenoh::ext::Serializer); eclipse-zenoh/zenoh-cpp ``include/zenoh/api/ext/serialization.hxx``
  (std::array is a sequence: length, then the elements). The bytes are compared with
  ``zenoh.ext.z_serialize`` (zenoh-ext, the same Rust serializer zenoh-cpp calls).
- RIHS01 hashes as ``ros2 topic info -v`` prints them on Jazzy (the Twist one is in the
  ROS 2 documentation's "Understanding topics" tutorial); they agree with published
  rmw_zenoh clients' tables (e.g. ``0/cmd_vel/geometry_msgs::msg::dds_::TwistStamped_/RIHS01_5f0f…``).
- Token strings from an independent rmw_zenoh-compatible zenoh-pico firmware's endpoint
  table (``@ros2_lv/0/100f0e0d0c0b0a090807060504030201/0/16/MS/%/%/nucleo_h743zi2/…``).
"""

from __future__ import annotations

import pytest
import xxhash
from zenoh.ext import Int64, z_serialize

from common import rmw_zenoh as rz
from common.errors import ConfigError, SchemaError

# ``ros2 topic info -v`` on Jazzy, "Topic type hash:" (see module doc)
JAZZY_HASHES = {
    "geometry_msgs/msg/Twist": "RIHS01_9c45bf16fe0983d80e3cfe750d6835843d265a9a6c46bd2e609fcddde6fb8d2a",
    "geometry_msgs/msg/TwistStamped": "RIHS01_5f0fcd4f81d5d06ad9b4c4c63e3ea51b82d6ae4d0558f1d475229b1121db6f64",
    "nav_msgs/msg/Odometry": "RIHS01_3cc97dc7fb7502f8714462c526d369e35b603cfc34d946e3f2eda2766dfec6e0",
    "sensor_msgs/msg/LaserScan": "RIHS01_64c191398013af96509d518dac71d5164f9382553fce5c1f8cca5be7924bd828",
    "sensor_msgs/msg/BatteryState": "RIHS01_4bee5dfce981c98faa6828b868307a0a73f992ed0789f374ee96c8f840e69741",
    "std_msgs/msg/String": "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18",
}
ZID = "100f0e0d0c0b0a090807060504030201"
# the independent firmware's node and subscription tokens (see module doc)
FIRMWARE_NODE = f"@ros2_lv/0/{ZID}/0/0/NN/%/%/nucleo_h743zi2"
FIRMWARE_SUB = (f"@ros2_lv/0/{ZID}/0/16/MS/%/%/nucleo_h743zi2/%nucleo%cmd_vel/"
                "geometry_msgs::msg::dds_::Twist_/"
                "RIHS01_9c45bf16fe0983d80e3cfe750d6835843d265a9a6c46bd2e609fcddde6fb8d2a/::,:,:,:,,")


@pytest.mark.parametrize("typename", sorted(JAZZY_HASHES))
def test_type_hashes_are_jazzys(typename):
    assert rz.type_hash(typename) == JAZZY_HASHES[typename]


def test_topic_keys():
    assert rz.topic_key(0, "/cmd_vel", "geometry_msgs/msg/Twist") == (
        "0/cmd_vel/geometry_msgs::msg::dds_::Twist_/" + JAZZY_HASHES["geometry_msgs/msg/Twist"])
    assert rz.topic_key(0, "/chatter", "std_msgs/msg/String") == (
        "0/chatter/std_msgs::msg::dds_::String_/RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db128"
        "8021743503259e948f6b1a18")
    assert rz.topic_key(42, "/nucleo/cmd_vel/", "geometry_msgs/msg/TwistStamped") == (
        "42/nucleo/cmd_vel/geometry_msgs::msg::dds_::TwistStamped_/"
        + JAZZY_HASHES["geometry_msgs/msg/TwistStamped"])
    assert rz.topic_name("odometry/filtered") == "/odometry/filtered"
    assert rz.topic_name("scan", "/robot1/") == "/robot1/scan"
    assert rz.ros_type_name("nav_msgs::msg::dds_::Odometry_") == "nav_msgs/msg/Odometry"
    with pytest.raises(ConfigError, match="pkg/msg/Name"):
        rz.dds_type_name("Twist")
    with pytest.raises(SchemaError):
        rz.ros_type_name("geometry_msgs/msg/Twist")


def test_tokens_match_an_independent_implementation():
    node = rz.Entity(0, ZID, 0, 0, rz.NODE, "/", "nucleo_h743zi2")
    assert node.token() == FIRMWARE_NODE
    sub = rz.Entity(0, ZID, 0, 16, rz.SUBSCRIPTION, "/", "nucleo_h743zi2",
                    topic="/nucleo/cmd_vel", typename="geometry_msgs/msg/Twist", qos=rz.DEFAULT_QOS)
    assert sub.token() == FIRMWARE_SUB
    back = rz.Entity.parse(FIRMWARE_SUB)
    assert back == rz.Entity(0, ZID, 0, 16, "MS", "/", "nucleo_h743zi2", topic="/nucleo/cmd_vel",
                             typename="geometry_msgs/msg/Twist",
                             hash=JAZZY_HASHES["geometry_msgs/msg/Twist"], qos=rz.DEFAULT_QOS)
    assert rz.Entity.parse(FIRMWARE_NODE).fq_node == "/nucleo_h743zi2"


def test_qos_field_leaves_rmw_zenoh_defaults_empty():
    # qos_to_keyexpr: reliable(1)/volatile(2)/keep last(1)/depth 42 are the defaults -> empty
    assert rz.DEFAULT_QOS.keyexpr() == "::,:,:,:,,"
    assert rz.RELIABLE_10.keyexpr() == "::,10:,:,:,,"
    assert rz.SENSOR_DATA.keyexpr() == "2::,5:,:,:,,"
    assert rz.LATCHED.keyexpr() == ":1:,1:,:,:,,"
    odd = rz.Qos(reliability=2, durability=1, history=2, depth=7, deadline=(5, 0),
                 lifespan=(60, 3000), liveliness=3, lease=(1, 2))
    assert odd.keyexpr() == "2:1:2,7:5,0:60,3000:3,1,2"
    for q in (rz.DEFAULT_QOS, rz.RELIABLE_10, rz.SENSOR_DATA, odd):
        assert rz.Qos.parse(q.keyexpr()) == q
    for bad in ("", "::,:,:,:", "x::,:,:,:,,", "::,:,:,:,,,"):
        with pytest.raises(SchemaError):
            rz.Qos.parse(bad)


def test_gid_is_xxh3_128_low_then_high_little_endian():
    h = xxhash.xxh3_128_intdigest(FIRMWARE_SUB.encode())
    expected = (h & (2**64 - 1)).to_bytes(8, "little") + (h >> 64).to_bytes(8, "little")
    assert rz.gid(FIRMWARE_SUB) == expected == xxhash.xxh3_128_digest(FIRMWARE_SUB.encode())[::-1]
    assert len(rz.Entity.parse(FIRMWARE_SUB).gid) == rz.GID_SIZE


def test_attachment_bytes_are_zenoh_ext_serializer_bytes():
    gid = bytes(range(100, 116))
    ours = rz.Attachment(7, 1_733_000_000_123_456_789, gid).encode()
    theirs = z_serialize((Int64(7), Int64(1_733_000_000_123_456_789), gid)).to_bytes()
    assert ours == theirs and len(ours) == rz.ATTACHMENT_SIZE == 33
    assert rz.Attachment.decode(theirs) == rz.Attachment(7, 1_733_000_000_123_456_789, gid)
    for bad in (b"", theirs[:-1], theirs + b"\x00", theirs[:16] + b"\x0f" + theirs[17:]):
        with pytest.raises(rz.AttachmentError):
            rz.Attachment.decode(bad)


def test_token_parse_refuses_garbage():
    for bad in ("", "rosbot/alive/x", "@ros2_lv/0/z/0/0/XX/%/%/n", "@ros2_lv/0/z/a/0/NN/%/%/n",
                FIRMWARE_SUB.rsplit("/", 1)[0], "@ros2_lv/0/z/0//NN/%/%/n"):
        with pytest.raises(SchemaError):
            rz.Entity.parse(bad)


def test_domain_from_the_environment():
    assert rz.default_domain({}) == 0
    assert rz.default_domain({"ROS_DOMAIN_ID": " 17 "}) == 17
    with pytest.raises(ConfigError, match="ROS_DOMAIN_ID='x'"):
        rz.default_domain({"ROS_DOMAIN_ID": "x"})
    with pytest.raises(ConfigError, match="0..232"):
        rz.default_domain({"ROS_DOMAIN_ID": "300"})
    with pytest.raises(ConfigError, match="0..232"):
        rz.check_domain(-1)
