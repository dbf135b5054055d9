"""Tracker core against synthetic scans (hand-checked values), and its input pairing."""

import math

import numpy as np
import pytest

from common.errors import ConfigError
from nodes.tracker import box, kernels
from nodes.tracker.__main__ import params_from
from nodes.tracker.core import Tracker, TrackerParams, cluster_points, scan_points, segments
from nodes.tracker.loop import TrackerLoop
from schemas.messages import Odometry, Scan

B = 360                     # 1 degree per beam, beam i at angle -pi + i deg
MS = 1_000_000


def beam(deg: float) -> int:
    return int(round(deg)) + 180


def make_scan(ranges, t=0) -> Scan:
    return Scan(stamp_ns=t, angle_min=-math.pi, angle_increment=2 * math.pi / B, range_min=0.2,
                range_max=25.0, ranges=np.asarray(ranges, dtype=np.float32))


def empty():
    return np.full(B, np.inf)


ORIGIN = Odometry(stamp_ns=0, x=0.0, y=0.0, yaw=0.0, v=0.0, w=0.0)


def face_scan(x_face: float, y_centre: float = 0.0, half: float = 0.15, t=0) -> Scan:
    """A flat face across the x axis at x = x_face, |y - y_centre| <= half, seen from (0, 0)."""
    r = empty()
    for i in range(B):
        a = -math.pi + i * 2 * math.pi / B
        if math.cos(a) > 0:
            y = x_face * math.tan(a)
            if abs(y - y_centre) <= half:
                r[i] = x_face / math.cos(a)
    return make_scan(r, t)


def test_points_are_world_frame_with_pose_and_sensor_offset():
    r = empty()
    r[beam(0)] = 1.0                           # straight ahead of the sensor
    r[beam(90)] = 30.0                         # beyond range_max: invalid
    scan = Scan(stamp_ns=0, angle_min=-math.pi, angle_increment=2 * math.pi / B, range_min=0.2,
                range_max=25.0, ranges=np.asarray(r, dtype=np.float32), sensor_x=0.1)
    pose = Odometry(stamp_ns=0, x=1.0, y=2.0, yaw=math.pi / 2, v=0.0, w=0.0)
    sp = scan_points(scan, pose, max_range=6.0)
    assert sp.beams.tolist() == [beam(0)]
    assert sp.xy[0] == pytest.approx((1.0, 2.0 + 0.1 + 1.0), abs=1e-6)   # sensor 0.1 m ahead, +y


def test_an_arc_of_returns_is_one_cluster_measured_at_its_box_centre():
    r = empty()
    r[beam(0):beam(4) + 1] = 2.0               # 5 returns on an arc of radius 2, 0..4 deg
    (cl,) = cluster_points(scan_points(make_scan(r), ORIGIN, 6.0), TrackerParams())
    # box in the principal axes (along the chord): across from the chord (2 cos 2deg from the
    # origin) to the arc's middle (2.0), so its centre lies at (2 cos 2deg + 2) / 2 along 2 deg
    mid = (2 * math.cos(math.radians(2)) + 2) / 2
    assert (cl.x, cl.y) == pytest.approx((mid * math.cos(math.radians(2)),
                                          mid * math.sin(math.radians(2))), abs=1e-4)
    assert cl.length == pytest.approx(2 * 2 * math.sin(math.radians(2)), abs=1e-4)  # chord 0.1395


def test_breakpoints_follow_the_adaptive_limit_and_beam_gaps():
    p = TrackerParams()
    r = empty()
    r[beam(0):beam(4) + 1] = 2.0
    r[beam(6):beam(9) + 1] = 2.0               # one beam without a return between
    # gap 2 beams: D_max = 2 sin 2deg / sin(30 - 2)deg + 3 * 0.01 = 0.179 m > 0.0698 m apart
    assert len(segments(scan_points(make_scan(r), ORIGIN, 6.0), p)) == 1
    r[beam(6):beam(9) + 1] = np.inf
    r[beam(8):beam(11) + 1] = 2.0              # three beams without a return: free space
    assert len(segments(scan_points(make_scan(r), ORIGIN, 6.0), p)) == 2
    r = empty()
    r[beam(0):beam(4) + 1] = 2.0
    r[beam(5):beam(9) + 1] = 2.5               # adjacent beams, 0.5 m deeper: a break
    assert len(segments(scan_points(make_scan(r), ORIGIN, 6.0), p)) == 2


def test_seam_joins_first_and_last_returns_and_small_or_long_clusters_drop():
    r = empty()
    r[[0, 1, 2, B - 2, B - 1]] = 1.0           # behind the robot, across the -pi/pi seam
    clusters = cluster_points(scan_points(make_scan(r), ORIGIN, 6.0), TrackerParams())
    assert len(clusters) == 1 and clusters[0].x == pytest.approx(-1.0, abs=2e-3)
    r = empty()
    r[beam(0):beam(1) + 1] = 2.0               # 2 points: noise
    assert cluster_points(scan_points(make_scan(r), ORIGIN, 6.0), TrackerParams()) == []
    wall = face_scan(1.0, half=3.0)            # a 6 m wall: structure, not an object
    assert cluster_points(scan_points(wall, ORIGIN, 6.0), TrackerParams()) == []


def test_kalman_step_matches_hand_computation():
    """Start at (0, 0); after dt = 0.1 s a measurement at (0.05, 0):
    P_xx = 0.05^2 + 0.1^2 * 1^2 + 0.1^4 / 4 = 0.012525, P_xv = 0.1 + 0.1^3 / 2 = 0.1005,
    S = P_xx + 0.05^2 = 0.015025 -> x = 0.05 * 0.012525 / 0.015025 = 0.041681,
    vx = 0.05 * 0.1005 / 0.015025 = 0.334443."""
    tr = Tracker(TrackerParams(confirm_hits=1))
    tr.update(face_scan(2.0), ORIGIN)
    x0 = tr.tracks.x[0, 0]
    tr.update(face_scan(2.05, t=100 * MS), Odometry(stamp_ns=100 * MS, x=0.0, y=0.0, yaw=0.0,
                                                    v=0.0, w=0.0))
    x1 = tr.objects(0).tracks[0]
    z = x0 + 0.05                              # the face's box centre moved 5 cm
    assert x1.x - x0 == pytest.approx((z - x0) * 0.012525 / 0.015025, abs=1e-4)
    assert x1.vx == pytest.approx((z - x0) * 0.1005 / 0.015025, abs=2e-3)


def test_constant_velocity_object_converges_and_keeps_its_id():
    tr = Tracker()
    out = None
    for k in range(40):                        # 0.3 m/s along +x, 0.1 m/s along +y for 4 s
        t = k * 100 * MS
        pose = Odometry(stamp_ns=t, x=0.0, y=0.0, yaw=0.0, v=0.0, w=0.0)
        out = tr.update(face_scan(1.5 + 0.03 * k, 0.01 * k, t=t), pose)
        if k < 2:
            assert out.tracks == ()            # confirmed at the third hit
    (track,) = out.tracks
    assert track.id == 1 and out.source == "tracker" and out.stamp_ns == 3900 * MS
    assert (track.vx, track.vy) == pytest.approx((0.3, 0.1), abs=0.02)
    assert track.yaw == pytest.approx(math.atan2(0.1, 0.3), abs=0.05)
    assert track.width == pytest.approx(0.3, abs=0.05)


def test_two_objects_keep_their_ids_and_a_lost_one_is_dropped():
    tr = Tracker()
    for k in range(5):
        t = k * 100 * MS
        scan = face_scan(2.0, 0.6, t=t)
        r = np.minimum(np.asarray(scan.ranges, float), np.asarray(face_scan(3.0, -0.6).ranges))
        out = tr.update(make_scan(r, t), ORIGIN)
    ids = {round(o.y, 1): o.id for o in out.tracks}
    assert set(ids) == {0.6, -0.6}
    for k in range(5, 10):                     # only the first one stays in view
        out = tr.update(face_scan(2.0, 0.6, t=k * 100 * MS), ORIGIN)
    assert [o.id for o in out.tracks] == [ids[0.6]]


def test_time_going_back_restarts_the_tracker():
    tr = Tracker(TrackerParams(confirm_hits=1))
    tr.update(face_scan(2.0, t=500 * MS), ORIGIN)
    assert tr.update(face_scan(2.0, t=0), ORIGIN).tracks[0].id == 1


def test_loop_pairs_scan_with_the_pose_of_its_stamp():
    lp = TrackerLoop(Tracker(TrackerParams(confirm_hits=1)))
    assert lp.on_message("scan", face_scan(2.0, t=100 * MS), 0.0) == []
    lp.on_message("odom", Odometry(stamp_ns=80 * MS, x=5.0, y=0.0, yaw=0.0, v=0.0, w=0.0), 0.0)
    out = lp.on_message("odom", Odometry(stamp_ns=100 * MS, x=1.0, y=0.0, yaw=0.0, v=0.0, w=0.0),
                        0.0)
    (topic, objects), = out
    assert topic == "objects" and objects.stamp_ns == 100 * MS
    assert objects.tracks[0].x == pytest.approx(3.0, abs=0.01)     # seen from x = 1
    lp.on_message("scan", face_scan(2.0, t=200 * MS), 1.0)
    assert lp.poll(3.9) == [] and lp.poll(4.1)[0][1].stamp_ns == 200 * MS   # pair timeout (3 s)
    assert lp.unpaired == 1


@pytest.mark.skipif(not kernels.HAVE_NUMBA, reason="numba not installed")
def test_numba_and_numpy_clustering_agree():
    rng = np.random.default_rng(4)
    scans = [face_scan(2.0, 0.6), face_scan(1.0, half=3.0), make_scan(empty())]
    r = empty()
    r[[0, 1, 2, B - 2, B - 1]] = 1.0                       # across the seam
    r[beam(40):beam(47) + 1] = 3.0 + rng.normal(0, 0.01, 8)
    scans.append(make_scan(r))
    r = np.where(rng.random(B) < 0.5, rng.uniform(0.5, 5.0, B), np.inf)   # clutter
    scans.append(make_scan(r))
    for scan in scans:
        sp = scan_points(scan, ORIGIN, 6.0)
        fast = cluster_points(sp, TrackerParams(use_numba=True))
        slow = cluster_points(sp, TrackerParams(use_numba=False))
        assert len(fast) == len(slow)
        for a, b in zip(fast, slow, strict=True):
            assert (a.x, a.y, a.length, a.width) == pytest.approx((b.x, b.y, b.length, b.width),
                                                                  abs=1e-9)


def test_settings_are_checked():
    assert params_from(["gate=0.7", "min_points=4"]) == TrackerParams(gate=0.7, min_points=4)
    assert params_from(["use_numba=false"]).use_numba is False
    with pytest.raises(ConfigError, match="not a bool"):
        params_from(["use_numba=maybe"])
    with pytest.raises(ConfigError, match="gate"):
        params_from(["gate=-1"])
    with pytest.raises(ConfigError, match="one of max_range"):
        params_from(["nope=1"])


def test_box_model_puts_a_seen_face_on_the_known_box():
    """A track that knows its object is 0.5 m deep (across its face-aligned frame), then sees
    only the face at x = 1.75 from the origin: the box centre is 0.25 m behind the face."""
    tr = Tracker(TrackerParams(confirm_hits=1))
    tr.update(face_scan(1.75), ORIGIN)
    assert abs(math.cos(tr.tracks.yaw[0])) < 0.05                    # the face's axis
    tr.tracks.size[0] = (0.3, 0.5)                 # along the face, across it (seen before)
    sp = scan_points(face_scan(1.75), ORIGIN, 6.0)
    (cl,) = cluster_points(sp, TrackerParams())
    fitted = tr._box(0, cl, sp.origin)
    assert (fitted.x, fitted.y) == pytest.approx((2.0, 0.0), abs=0.01)
    assert (cl.x, cl.y) == pytest.approx((1.75, 0.0), abs=0.01)     # the plain cluster centre
    # seen from beyond the box the other face is the near one
    assert box.anchor(1.0, 1.1, 0.5, 2.0) == pytest.approx(0.85)
    assert box.anchor(1.0, 1.1, 0.5, 0.0) == pytest.approx(1.25)
    assert box.anchor(1.0, 1.5, 0.5, 0.0) == pytest.approx(1.25)   # all of it seen
    assert box.anchor(1.0, 1.1, 0.5, 1.05) == pytest.approx(1.05)  # facing it: both ends


def test_a_standing_object_keeps_its_heading_under_measurement_noise():
    """A face jittering by 3 cm: the filter's velocity stays within its own uncertainty, so the
    heading stays the first one (the velocity's direction would be noise)."""
    rng = np.random.default_rng(1)
    tr = Tracker()
    for k in range(50):
        t = k * 100 * MS
        out = tr.update(face_scan(2.0 + rng.normal(0, 0.03), rng.normal(0, 0.03), t=t),
                        Odometry(stamp_ns=t, x=0.0, y=0.0, yaw=0.0, v=0.0, w=0.0))
    (track,) = out.tracks
    assert abs(math.cos(track.yaw)) < 0.05                           # the face's axis
    assert (track.length, track.width) == pytest.approx((0.3, 0.0), abs=0.08)
    assert box.turned((0.5, 0.3), 0.3) == (0.5, 0.3) and box.turned((0.5, 0.3), 1.2) == (0.3, 0.5)


def test_box_extents_compiled_and_numpy_agree():
    pts = np.random.default_rng(2).normal(size=(17, 2))
    for yaw in (0.0, 0.7, -2.0):
        slow = box.fit(pts, yaw, (3.0, 2.0), (5.0, 1.0), compiled=False)
        fast = box.fit(pts, yaw, (3.0, 2.0), (5.0, 1.0), compiled=True)
        assert fast == pytest.approx(slow, abs=1e-12)
