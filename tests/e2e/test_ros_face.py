"""``papf run --ros-face``: a ROS 2 client over rmw_zenoh that is not ours finds the stack.

The client is raw zenoh-python with keys written from rmw_zenoh's format (literal keys;
RIHS01 hashes as ``ros2 topic info -v`` prints them on Jazzy) and ``rosbags`` for CDR — not
:mod:`common.rmw_zenoh`. It finds our nodes and publishers by their liveliness tokens,
decodes ``/scan``, ``/odom`` and ``/tf``, and a ``/goal_pose`` it publishes is reached.
"""

from __future__ import annotations

import json
import subprocess
import sys
import threading
import time

import pytest
import zenoh
from rosbags.typesys import Stores, get_typestore
from zenoh.ext import Int64, z_serialize

from common.transport import zenoh_config
from tests.support.cli import papf
from tests.support.e2e import free_port

DOMAIN = 9
STORE = get_typestore(Stores.ROS2_JAZZY)
KEYS = {   # topic -> (type, rmw_zenoh key)
    "scan": ("sensor_msgs/msg/LaserScan", f"{DOMAIN}/scan/sensor_msgs::msg::dds_::LaserScan_/"
             "RIHS01_64c191398013af96509d518dac71d5164f9382553fce5c1f8cca5be7924bd828"),
    "odom": ("nav_msgs/msg/Odometry", f"{DOMAIN}/odom/nav_msgs::msg::dds_::Odometry_/"
             "RIHS01_3cc97dc7fb7502f8714462c526d369e35b603cfc34d946e3f2eda2766dfec6e0"),
    "tf": ("tf2_msgs/msg/TFMessage", f"{DOMAIN}/tf/tf2_msgs::msg::dds_::TFMessage_/"
           "RIHS01_e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087"),
}
GOAL_KEY = (f"{DOMAIN}/goal_pose/geometry_msgs::msg::dds_::PoseStamped_/"
            "RIHS01_10f3786d7d40fd2b54367835614bff85d4ad3b5dab62bf8bca0cc232d73b4cd8")
GOAL = (2.0, 0.0)     # short of the world's goal (open: 5 m ahead), in frame odom


def _goal_pose(x: float, y: float) -> bytes:
    c = STORE.types
    msg = c["geometry_msgs/msg/PoseStamped"](
        header=c["std_msgs/msg/Header"](stamp=c["builtin_interfaces/msg/Time"](sec=0, nanosec=0),
                                        frame_id="odom"),
        pose=c["geometry_msgs/msg/Pose"](
            position=c["geometry_msgs/msg/Point"](x=x, y=y, z=0.0),
            orientation=c["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0)))
    return bytes(STORE.serialize_cdr(msg, "geometry_msgs/msg/PoseStamped"))


@pytest.mark.slow   # the slow tier (make test-quick leaves it out)
@pytest.mark.e2e
def test_a_third_party_ros2_client_finds_decodes_and_steers_the_stack():
    port = free_port()
    proc = subprocess.Popen(
        [sys.executable, "-m", "papf", "run", "--world", "open", "--planner", "apf", "--realtime",
         "--port", str(port), "--namespace", "face1", "--ros-face", "--ros-face-domain",
         str(DOMAIN), "--json", "--timeout", "60"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    got: dict[str, list] = {t: [] for t in KEYS}
    tokens: list[str] = []
    try:
        deadline = time.monotonic() + 120.0
        session = None
        while session is None and time.monotonic() < deadline and proc.poll() is None:
            try:
                session = zenoh.open(zenoh_config("client", [f"tcp/127.0.0.1:{port}"]))
            except zenoh.ZError:
                time.sleep(0.5)
        assert session is not None, proc.stderr.read() if proc.poll() is not None else "no router"
        subs = [session.declare_subscriber(key, lambda s, t=t, ty=ty: got[t].append(
            STORE.deserialize_cdr(s.payload.to_bytes(), ty))) for t, (ty, key) in KEYS.items()]
        while time.monotonic() < deadline and not all(got.values()):
            time.sleep(0.1)
        assert all(got.values()), {t: len(v) for t, v in got.items()}
        tokens = [str(r.ok.key_expr) for r in session.liveliness().get(
            f"@ros2_lv/{DOMAIN}/**", timeout=3.0) if r.ok]
        stop = threading.Event()

        def send_goal():     # like RViz's "2D Goal Pose", repeated until the run ends
            seq = 0
            while not stop.is_set():
                seq += 1
                session.put(GOAL_KEY, _goal_pose(*GOAL), attachment=z_serialize(
                    (Int64(seq), Int64(time.time_ns()), bytes(16))).to_bytes())
                stop.wait(0.5)

        sender = threading.Thread(target=send_goal, daemon=True)
        sender.start()
        out, err = proc.communicate(timeout=180)
        stop.set()
        sender.join(2.0)
        for s in subs:
            s.undeclare()
        session.close()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    for node in ("papf_lidar_sim", "papf_base_driver", "papf_planner", "papf_energy_meter",
                 "papf_robot_state_publisher"):
        assert any(t.endswith(f"/NN/%/%/{node}") for t in tokens), (node, tokens)
    for topic, (_, key) in KEYS.items():
        dds, rihs = key.rsplit("/", 2)[1:]
        assert any("/MP/%/%/papf_" in t and f"/%{topic}/{dds}/{rihs}/" in t for t in tokens), topic
    assert any("/MS/%/%/papf_planner/%goal_pose/geometry_msgs::msg::dds_::PoseStamped_/" in t
               for t in tokens)
    assert got["scan"][-1].header.frame_id == "laser" and len(got["scan"][-1].ranges) > 0
    assert got["odom"][-1].header.frame_id == "odom"
    tf = next(m.transforms[0] for m in reversed(got["tf"])
              if m.transforms[0].header.frame_id == "odom")
    assert (tf.header.frame_id, tf.child_frame_id) == ("odom", "base_link")
    wheels = {t.child_frame_id for m in got["tf"] for t in m.transforms
              if t.header.frame_id == "base_link"}
    assert wheels == {f"{w}_wheel_link" for w in ("front_left", "front_right", "rear_left",
                                                  "rear_right")}   # RViz turns the URDF's wheels
    result = json.loads(out.strip().splitlines()[-1])
    assert result["outcome"] == "reached", err[-2000:]
    assert result["path_length_m"] == pytest.approx(GOAL[0], abs=0.4)   # /goal_pose, not 5 m


@pytest.mark.e2e
def test_face_refuses_a_domain_where_a_robot_takes_cmd_vel(router, session):
    """A robot's controller subscribes /cmd_vel (rmw_zenoh token, written literally): the
    face's ungated commands would drive it, so the face exits 2 with one line."""
    token = session.liveliness().declare_token(
        f"@ros2_lv/{DOMAIN}/100f0e0d0c0b0a090807060504030201/0/3/MS/%/%/controller_manager/"
        "%cmd_vel/geometry_msgs::msg::dds_::Twist_/"
        "RIHS01_9c45bf16fe0983d80e3cfe750d6835843d265a9a6c46bd2e609fcddde6fb8d2a/::,10:,:,:,,")
    try:
        r = subprocess.run([sys.executable, "-m", "nodes.ros_face", "--ros-domain", str(DOMAIN),
                            "--connect", router, "--namespace", "face2"],
                           capture_output=True, text=True, timeout=120)
    finally:
        token.undeclare()
    assert r.returncode == 2, r.stderr
    assert "/controller_manager subscribe /cmd_vel" in r.stderr and "Traceback" not in r.stderr


def test_launch_refuses_the_face_on_the_robots_domain():
    r = papf("launch", "laptop", "--ros", "rmw_zenoh", "--ros-domain", "3", "--ros-face",
             "--ros-face-domain", "3", "--world", "open", "--connect", "tcp/127.0.0.1:7",
             "--dry-run", timeout=120)
    assert r.returncode == 2 and "--ros-face-domain" in r.stderr and r.stdout == ""
