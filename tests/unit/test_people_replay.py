"""Real people replayed as recorded: ``[[people_replay]]`` (worlds/people_replay.py), in the
crowd, the driver's physics and ``sim/people``, the LiDAR's bodies, the crowd's measures.

The committed files are small ones made here in the ETH/UCY benchmarks' form (``frame id x
y``, frames at 25 fps stepping by 10, ids and frames written as floats as they ship them).
If a real ETH/UCY file is given in ``PAPF_ETH_UCY_FILE``, the last test replays it too.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pytest

from common.crowd import Crowd
from common.errors import WorldError
from worlds import load_world
from worlds.people_replay import replay_state

S = 1_000_000_000

# person 1 walks +x at 1 m/s from frame 0 to 100 (0-4 s); person 2 appears at frame 50 (2 s)
# and walks -y; person 3 is gone before a run that starts at from_s = 6 s
TRACKS = """\
0.0\t1.0\t0.0\t0.0
10.0\t1.0\t0.4\t0.0
20.0\t1.0\t0.8\t0.0
50.0\t2.0\t2.0\t1.0
60.0\t2.0\t2.0\t0.6
100.0\t1.0\t4.0\t0.0
100.0\t2.0\t2.0\t-1.0
"""


def write_world(tmp: Path, rows: str = TRACKS, extra: str = "", name: str = "tracks.txt",
                robot=(0.0, 3.0)) -> Path:
    (tmp / name).write_text(rows, encoding="utf-8")
    world = tmp / "replay.toml"
    world.write_text(f"""name = "replay"
[robot]
start = [{robot[0]}, {robot[1]}, 0.0]
[goal]
position = [8.0, 3.0]
[[people_replay]]
file = "{name}"
format = "eth-ucy"
{extra}
""", encoding="utf-8")
    return world


def test_a_replay_file_gives_one_track_per_person_in_run_time(tmp_path):
    w = load_world(write_world(tmp_path))
    (spec,) = w.people_replay
    assert (spec.fps, spec.from_s, spec.offset, spec.radius) == (25.0, 0.0, (0.0, 0.0), 0.25)
    one, two = spec.tracks
    assert (one.id, two.id) == ("1", "2")
    assert one.times == (0.0, 0.4, 0.8, 4.0) and two.first_s == pytest.approx(2.0)
    assert w.has_people and w.n_people == 2 and not w.people


def test_positions_are_linear_between_rows_and_absent_outside_them(tmp_path):
    one, two = load_world(write_world(tmp_path)).replayed
    x, y, vx, vy = replay_state(one, 2.4)              # between frames 20 (0.8 s) and 100 (4 s)
    assert (x, y) == pytest.approx((0.8 + 1.6 / 3.2 * 3.2, 0.0))
    assert (vx, vy) == pytest.approx((1.0, 0.0))
    assert replay_state(two, 1.99) is None and replay_state(two, 4.01) is None
    assert replay_state(two, 2.2)[:2] == pytest.approx((2.0, 0.8))


def test_fps_from_s_and_offset_move_the_recording(tmp_path):
    w = load_world(write_world(tmp_path, extra="fps = 12.5\nfrom_s = 1.0\noffset = [10.0, -5.0]"
                               "\nradius = 0.3"))
    one = w.replayed[0]
    assert one.times[0] == pytest.approx(-1.0)          # frame 0 is 1 s before run time 0
    assert one.xy[0] == (10.0, -5.0) and w.people_replay[0].radius == 0.3
    assert replay_state(one, 0.0)[:2] == pytest.approx((10.5, -5.0))   # file time 1 s: x 0.5 m


def test_a_person_gone_before_the_run_starts_is_dropped(tmp_path):
    w = load_world(write_world(tmp_path, extra="from_s = 5.0"))
    assert w.n_people == 0 and not w.replayed


@pytest.mark.parametrize("rows, extra, says", [
    (TRACKS, 'format = "trajnet"', None),
    ("0 1 0.0\n", "", "tracks.txt:1: expected 4 columns 'frame id x y', got 3"),
    ("0 1 0 0\n10 1 0.4 zero\n", "", "tracks.txt:2: 'frame id x y' must be numbers"),
    ("0 1 0 0\n10 1 nan 0\n", "", "tracks.txt:2: a value is not finite"),
    ("10 1 0 0\n10 1 0.4 0\n", "", "tracks.txt:2: person 1 at frame 10 after frame 10"),
    ("", "", "has no rows"),
    ("0 1 2000 0\n", "", "beyond the 1000 m"),
    (TRACKS, "fps = 0", "fps: must be > 0"),
    (TRACKS, "from_s = -1", "must be >= 0 s"),
    (TRACKS, "radius = 3", "wider than a person"),
    (TRACKS, "speed = 1", "unknown key"),
])
def test_a_bad_replay_is_refused_in_one_line_naming_file_and_line(tmp_path, rows, extra, says):
    if says is None:   # the format key itself, written once
        world = write_world(tmp_path, rows)
        world.write_text(world.read_text().replace('format = "eth-ucy"', extra))
        says = "'trajnet' is not a known track format (known: eth-ucy)"
    else:
        world = write_world(tmp_path, rows, extra)
    with pytest.raises(WorldError) as err:
        load_world(world)
    assert says in str(err.value) and "\n" not in str(err.value)


def test_a_missing_track_file_is_named(tmp_path):
    world = write_world(tmp_path)
    (tmp_path / "tracks.txt").unlink()
    with pytest.raises(WorldError, match=r"people_replay\[0\]\.file: track file .*tracks.txt"
                                         r"' does not exist"):
        load_world(world)


def test_the_crowd_places_replayed_people_as_recorded(tmp_path):
    w = load_world(write_world(tmp_path))
    crowd = Crowd(w.people, w, seed=0)
    seen = []
    for _ in range(250):                                 # 5 s at the driver's 20 ms
        seen.append((round(crowd.time_s, 9), crowd.positions.copy(), crowd.radii.copy()))
        crowd.step(0.02, [(0.0, 3.0, 0.0, 0.0)])
    for t, xy, r in seen:
        for track, (x, y), radius in zip(w.replayed, xy, r, strict=True):
            state = replay_state(track, t)
            if state is None:
                assert radius == 0.0
            else:
                assert radius == 0.25 and (x, y) == pytest.approx(state[:2], abs=1e-9)


def test_the_driver_publishes_them_puts_them_in_the_physics_and_the_lidar(tmp_path):
    from nodes.world_sim.core import WorldCore

    w = load_world(write_world(tmp_path))
    with WorldCore(w, seed=0) as core:
        samples = []
        while core.t_ns <= 5 * S:
            out = core.outputs()
            people = dict(out)["sim/people"]
            samples.append((core.t_ns / S, people))
            if core.t_ns == 3 * S:
                bodies = dict(out)["sim/bodies"]
                assert bodies.person_radius == (0.25, 0.25)
                assert (bodies.person_x[0], bodies.person_y[1]) == pytest.approx((3.0, -0.0))
            core.advance()
    for t, msg in samples:        # where the file says, linear between rows (a few cm: exact)
        for track, x, y, r in zip(w.replayed, msg.x, msg.y, msg.radius, strict=True):
            state = replay_state(track, t)
            assert (r == 0.0) == (state is None)
            if state is not None:
                assert math.hypot(x - state[0], y - state[1]) < 0.02


def test_a_replayed_person_walking_into_a_standing_robot_caused_the_collision(tmp_path):
    from nodes.world_sim.core import WorldCore

    rows = "0 7 3.0 0.0\n100 7 -1.0 0.0\n"               # walks -x through the robot at 1 m/s
    w = load_world(write_world(tmp_path, rows, robot=(0.0, 0.0)))
    with WorldCore(w, seed=0) as core:
        events = []
        while core.t_ns < 4 * S and not events:
            if core.is_scan_instant():
                from schemas.messages import Twist

                core.command(Twist(stamp_ns=core.t_ns, v=0.0, w=0.0))
            core.advance()
            events += [m for t, m in core.outputs() if t == "events" and m.kind == "collision"]
    assert events and events[0].detail == "person 0, caused by the person"


def test_the_offline_crowd_and_its_measures_see_them_only_while_there(tmp_path):
    from papf.offline.run import simulate

    rows = "0 1 4.0 6.0\n250 1 4.0 4.2\n"   # comes to stand 1.2 m beside the path, then gone
    r = simulate(write_world(tmp_path, rows), "papf", seed=0, max_time_s=120.0)
    robot = r.crowd["robots"][0]
    assert r.outcome == "reached" and robot["collisions"] == 0
    run = r.trace
    assert run.shown.shape == run.people.shape[:2]
    assert (run.shown[run.times > 10.0] == 0).all() and (run.shown[run.times < 9.9] > 0).all()
    assert robot["social_n"] == 1 and robot["intimate_n"] == 0


@pytest.mark.skipif(not os.environ.get("PAPF_ETH_UCY_FILE"),
                    reason="set PAPF_ETH_UCY_FILE to a real ETH/UCY track file to replay it")
def test_a_real_eth_ucy_file_is_read_and_replayed(tmp_path):
    path = Path(os.environ["PAPF_ETH_UCY_FILE"]).resolve()
    world = tmp_path / "real.toml"
    world.write_text(f'[goal]\nposition = [8.0, 3.0]\n[[people_replay]]\nfile = "{path}"\n',
                     encoding="utf-8")
    w = load_world(world)
    crowd = Crowd(w.people, w, seed=0)
    for _ in range(500):
        crowd.step(0.02, [(0.0, 3.0, 0.0, 0.0)])
        here = crowd.radii > 0
        assert np.isfinite(crowd.positions[here]).all()
