"""Issue 20, second round: the holes a fresh probe found after the first round held.

A bounded ``papf topic echo`` inbox, terminal-safe text everywhere (errors, logs, node
names), the attraction-to-repulsion balance, the goal tolerance floor, the outputs of plan,
report, bench and view under the one output rule, launch's preflight, and the crowd and
traffic experiments' journals. Property-based where the input space is open.
"""

from __future__ import annotations

import io
import logging

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from common.text import MAX_LINE_CHARS, SafeLogFilter, safe_line, safe_text
from papf.bus.topics import Inbox, _echo

SETTINGS = settings(max_examples=60, deadline=None)


# -- papf topic echo: a flood is dropped oldest-first, counted, and said -------------------------
@SETTINGS
@given(st.lists(st.integers(0, 3000), min_size=1, max_size=300))
def test_inbox_stays_within_its_bounds_and_keeps_the_newest(sizes):
    inbox = Inbox(None, "x", max_items=50, max_bytes=20_000)
    for i, n in enumerate(sizes):
        inbox.put(f"k{i}", b"x" * n, float(i))
        assert len(inbox) <= 50
        assert len(inbox) == 1 or sum(len(d) for _, d, _ in inbox._items) <= 20_000
    assert inbox.dropped + len(inbox) == len(sizes)
    assert inbox._items[-1][0] == f"k{len(sizes) - 1}"   # the newest is never the one dropped


def test_echo_under_a_flood_says_it_dropped_and_how_many():
    inbox = Inbox(None, "x", max_items=10)
    for i in range(1000):
        inbox.put("rosbot/odom", b"\x80", float(i))
    printed, notes = [], []
    shown = _echo(inbox, printed.append, 0, 0.0, None, 8, False, lambda: len(printed) >= 10,
                  notes.append)
    assert shown == 10 and inbox.dropped == 990
    assert len(notes) == 1 and "dropped" in notes[0]


# -- terminal text -------------------------------------------------------------------------------
@SETTINGS
@given(st.text(max_size=2000), st.booleans())
def test_safe_text_never_passes_a_control_character(text, keep):
    out = safe_text(text, 300, keep_newlines=keep)
    assert all(c.isprintable() or (keep and c == "\n") for c in out)
    assert len(out) <= 300 * 10 + 40   # an escaped character is at most 10 long (\U0010ffff)


def test_an_error_quoting_a_hostile_world_name_is_one_short_safe_line(capsys):
    from papf.cli import main

    name = "\x1b]0;owned\x07\x1b[2J" + "w" * 100_000
    assert main(["plan", "--world", name]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "\x1b" not in err and "\x07" not in err
    assert len(err) < MAX_LINE_CHARS + 100


def test_a_usage_error_quoting_the_user_is_escaped(capsys):
    from papf.cli import main

    with pytest.raises(SystemExit) as exc:
        main(["run", "--planner", "\x1b[31mred" + "p" * 5000])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "\x1b" not in err and len(err) < MAX_LINE_CHARS + 200


def test_log_lines_show_escape_sequences_never_run_them():
    stream = io.StringIO()
    handler = logging.StreamHandler(stream)
    handler.addFilter(SafeLogFilter())
    log = logging.getLogger("test_hostile_round2")
    log.addHandler(handler)
    try:
        log.warning("ignored a goal from %s", "\x1b[2Jpeer\r" + "z" * 10_000)
    finally:
        log.removeHandler(handler)
    line = stream.getvalue()
    assert "\x1b" not in line and "\r" not in line and "\\x1b[2Jpeer" in line
    assert len(line) < MAX_LINE_CHARS + 40


def test_safe_line_cuts_a_flood_and_says_how_long():
    assert safe_line("a" * 100_000).endswith("(100,000 chars)")   # a flood is cut
    assert safe_line("a" * 10_000) == "a" * 10_000                  # a message never


# -- goal tolerance floor ------------------------------------------------------------------------
@pytest.mark.parametrize("tolerance", [0.0, 1e-300, -1.0, 0.004])
def test_a_goal_tolerance_below_the_floor_is_refused_by_goal_and_worlds(tolerance, capsys):
    from common.errors import WorldError
    from papf.cli import main
    from worlds import parse_world

    with pytest.raises(SystemExit) as exc:
        main(["goal", "1", "0", "--tolerance", repr(tolerance)])
    assert exc.value.code == 2 and "0.005" in capsys.readouterr().err
    with pytest.raises(WorldError, match="at least 0.005 m"):
        parse_world({"goal": {"position": [1.0, 0.0], "tolerance": tolerance}}, "t")


@pytest.mark.parametrize("tolerance", [0.0, 1e-300, -5.0])
def test_a_bus_goal_with_a_tolerance_below_the_floor_is_reached_at_the_floor(tolerance):
    import math

    import numpy as np

    from common.robot import GOAL_TOLERANCE_MIN_M
    from nodes.planner.apf.strategy import APFStrategy
    from nodes.planner.core import Planner
    from schemas.messages import Goal, Odometry, Scan

    pl = Planner(APFStrategy())
    pl.set_goal(Goal(stamp_ns=1, x=1.0, y=0.0, tolerance=tolerance))
    scan = Scan(stamp_ns=2, angle_min=0.0, angle_increment=2 * math.pi / 8, range_min=0.2,
                range_max=10.0, ranges=np.full(8, np.inf, dtype=np.float32))
    near = 1.0 - 0.9 * GOAL_TOLERANCE_MIN_M
    status = pl.step(scan, Odometry(stamp_ns=2, x=near, y=0.0, yaw=0.0, v=0.0, w=0.0))[2]
    assert status.state == "reached"


# -- papf launch / run preflight: configs, bridge namespace, view port ---------------------------
def _launch(**kw):
    from papf.launch.profile import LaunchOptions

    values = {"world": "energy", **kw.pop("values", {})}
    return LaunchOptions(kw.pop("profile", "sim"), values=values, **kw)


def _config_cases(tmp_path):
    bad = tmp_path / "bad.json5"
    bad.write_text("{ mode: 'router', listen: { endpoints: [ ")
    big = tmp_path / "big.json5"
    big.write_bytes(b" " * (2 * 1024 * 1024))
    binary = tmp_path / "bin.json5"
    binary.write_bytes(b"\xff\xfe\x00garbage")
    return [(str(tmp_path / "missing.json5"), "does not exist"), (str(tmp_path), "is a directory"),
            (str(bad), "not a valid Zenoh JSON5"), (str(big), "bytes is not a Zenoh config"),
            (str(binary), "not a valid Zenoh JSON5")]


def test_launch_refuses_a_bad_router_or_node_config_before_anything_starts(tmp_path):
    from common.errors import ConfigError
    from papf.launch.preflight import check_launch
    from papf.launch.profile import load_profile

    for path, match in _config_cases(tmp_path):
        for opt in (_launch(router_config=path), _launch(zenoh_config=path)):
            with pytest.raises(ConfigError, match=match):
                check_launch(opt, load_profile("sim"))
    good = tmp_path / "good.json5"
    good.write_text('{"mode": "router"}')
    check_launch(_launch(router_config=str(good)), load_profile("sim"))


@pytest.mark.parametrize("ns,match", [("a//b", "plain key"), ("lab/*", "plain key"),
                                      ("has space", "plain key"), ("rosbot", "overlaps")])
def test_launch_refuses_a_bridge_namespace_that_makes_no_key(ns, match):
    from common.errors import ConfigError
    from papf.launch.preflight import check_launch
    from papf.launch.profile import load_profile

    with pytest.raises(ConfigError, match=match):
        check_launch(_launch(values={"bridge_namespace": ns}), load_profile("sim"))


def test_a_busy_or_out_of_range_view_port_is_refused_before_anything_starts(capsys):
    import socket

    from common.errors import ConfigError
    from papf.cli import main
    from papf.launch.preflight import check_launch
    from papf.launch.profile import load_profile

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        busy = s.getsockname()[1]
        with pytest.raises(ConfigError, match=f"--view {busy}: something already listens"):
            check_launch(_launch(values={"view": busy}), load_profile("sim"))
    for bad in ("99999", "0", "nan", "-1"):
        with pytest.raises(SystemExit) as exc:
            main(["launch", "sim", "--view", bad])
        assert exc.value.code == 2 and "--view" in capsys.readouterr().err


# -- the one output rule for plan, report, view --layout and the benchmarks' CSVs ----------------
def test_plan_refuses_its_outputs_before_the_run(tmp_path, capsys):
    import os
    import time

    from papf.cli import main
    from worlds import world_path

    world = tmp_path / "w.toml"
    world.write_text(world_path("papf-test-1").read_text())
    link = tmp_path / "w.csv"
    os.link(world, link)                 # --out a hard link of the world: never, even forced
    mine = tmp_path / "mine.png"
    mine.write_bytes(b"user's")
    for argv, match in ((["--out", str(link), "--force"], "is the input"),
                        (["--plot", str(mine)], "already exists"),
                        (["--out", str(tmp_path / "p.txt")], ".csv or .json"),
                        (["--plot", str(tmp_path / "no" / "p.png")], "does not exist")):
        t0 = time.monotonic()
        assert main(["plan", "--world", str(world), *argv]) == 2
        assert time.monotonic() - t0 < 5.0        # before the run, not after it
        assert match in capsys.readouterr().err
    assert mine.read_bytes() == b"user's" and world.read_text() == link.read_text()


def test_a_forced_plot_replaces_a_symlink_never_its_target(tmp_path):
    from papf.cli import main

    precious = tmp_path / "run.mcap"
    precious.write_bytes(b"recording")
    plot = tmp_path / "p.png"
    plot.symlink_to(precious)
    assert main(["plan", "--world", "papf-test-1", "--timeout", "3", "--plot", str(plot),
                 "--force"]) in (0, 5)
    assert precious.read_bytes() == b"recording"
    assert not plot.is_symlink() and plot.read_bytes()[:4] == b"\x89PNG"


def test_view_layout_refuses_an_existing_file_and_follows_no_symlink(tmp_path, capsys):
    from papf.cli import main

    target = tmp_path / "user.json"
    target.write_text("mine")
    link = tmp_path / "layout.json"
    link.symlink_to(target)
    assert main(["view", "--layout", str(link)]) == 2
    assert "already exists" in capsys.readouterr().err
    assert main(["view", "--layout", str(link), "--force"]) == 0
    assert target.read_text() == "mine" and not link.is_symlink()


def test_report_refuses_to_replace_an_earlier_report_unless_forced(tmp_path):
    from common.outfiles import OutputError
    from papf.report import build_report
    from tests.support.recordings import write_synthetic

    runs = tmp_path / "runs"
    runs.mkdir()
    write_synthetic(runs / "apf-1.mcap", "apf", seed=1, speed=0.4)
    out = tmp_path / "out"
    out.mkdir()
    (out / "report.md").write_text("the user's notes")
    with pytest.raises(OutputError, match=r"already holds a report \(report.md\); use --force"):
        build_report([runs], out)
    assert sorted(p.name for p in out.iterdir()) == ["report.md"]     # nothing moved
    assert (out / "report.md").read_text() == "the user's notes"
    (out / "charge.png").symlink_to(runs / "apf-1.mcap")   # a name that is an input
    with pytest.raises(OutputError, match="is the input"):
        build_report([runs], out, force=True)
    (out / "charge.png").unlink()
    build_report([runs], out, force=True)
    assert (out / "report.md").read_text() != "the user's notes"


@SETTINGS
@given(st.binary(min_size=1, max_size=200))
def test_a_benchmark_csv_appends_only_to_its_own_table(tmp_path_factory, head):
    from bench.csvrows import write_rows
    from common.outfiles import OutputError

    d = tmp_path_factory.mktemp("csv")
    other = d / "other.csv"
    other.write_bytes(head)
    if head.split(b"\n")[0].rstrip(b"\r") != b"a,b":
        with pytest.raises(OutputError, match="not this benchmark's CSV"):
            write_rows(other, ("a", "b"), [{"a": 1, "b": 2}], append=True)
        assert other.read_bytes() == head


def test_a_benchmark_csv_never_writes_through_a_symlink_or_into_a_directory(tmp_path):
    from bench.csvrows import replace_label, write_rows
    from common.outfiles import OutputError

    ours = tmp_path / "ours.csv"
    write_rows(ours, ("a", "b"), [{"a": 1, "b": 2}], append=True)
    write_rows(ours, ("a", "b"), [{"a": 3, "b": 4}], append=True)
    assert ours.read_text().splitlines() == ["a,b", "1,2", "3,4"]
    link = tmp_path / "link.csv"
    link.symlink_to(ours)
    for path in (link, tmp_path):
        with pytest.raises(OutputError):
            write_rows(path, ("a", "b"), [{"a": 5}], append=True)
        with pytest.raises(OutputError):
            replace_label(path, ("a", "b", "label"), "x", [{"a": 5}])
    assert ours.read_text().splitlines() == ["a,b", "1,2", "3,4"]


# -- the crowd and traffic experiments keep every finished run -----------------------------------
def test_crowd_keeps_each_finished_run_and_resumes_after_an_interrupt(tmp_path, monkeypatch):
    from papf.experiments import crowd

    real, calls = crowd.run_crowd_job, []

    def interrupted_second(job):
        calls.append(job.people)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return real(job)

    monkeypatch.setattr(crowd, "run_crowd_job", interrupted_second)
    with pytest.raises(KeyboardInterrupt):
        crowd.run_crowd(tmp_path, planners=["apf"], people=[0, 2], seeds=[0], timeout_s=5)
    assert len(list((tmp_path / "runs").glob("*.json"))) == 1
    calls.clear()
    monkeypatch.setattr(crowd, "run_crowd_job", lambda job: calls.append(job.people) or real(job))
    crowd.run_crowd(tmp_path, planners=["apf"], people=[0, 2], seeds=[0], timeout_s=5)
    assert calls == [2]                  # the finished run was taken from its file
    rows = (tmp_path / "crowd.csv").read_text().splitlines()
    assert len(rows) == 3 and rows[1].split(",")[4] == "0"   # in job order (people)


def test_traffic_keeps_each_finished_run_and_resumes_after_an_interrupt(tmp_path, monkeypatch):
    from papf.experiments import traffic

    calls = []

    def fake_stack(world, planner, seed, timeout_s, **kw):
        calls.append(planner)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return object()

    def fake_row(name, planner, objects, trial, mcap):
        return {"world": name, "planner": planner, "objects": objects, "seed": 0,
                "outcome": "reached", "duration_s": 1.0, "path_length_m": 1.0, "collisions": 0,
                "left_road": 0, "lane_changes": 0, "min_speed_mps": 0.1, "max_speed_mps": 0.2,
                "wall_time_s": 1.0, "reason": ""}

    monkeypatch.setattr(traffic, "run_stack", fake_stack)
    monkeypatch.setattr(traffic, "road_row", fake_row)
    cases = (("apf", "none"), ("papf", "none"), ("arapf", "none"))
    world = traffic.ROAD_WORLDS[0]
    with pytest.raises(KeyboardInterrupt):
        traffic.run_traffic(tmp_path, [world], cases, echo=lambda _l: None)
    calls.clear()
    monkeypatch.setattr(traffic, "run_stack", lambda *a, **k: calls.append(a[1]) or object())
    rows = traffic.run_traffic(tmp_path, [world], cases, echo=lambda _l: None)
    assert calls == ["papf", "arapf"] and [r["planner"] for r in rows] == ["apf", "papf", "arapf"]


# -- every numeric option of every command: nan, inf, huge, negative refused by argparse ---------
NUMERIC_OPTIONS = [
    (["teleop"], o) for o in ("--max-v", "--max-w", "--step-v", "--step-w", "--rate")
] + [(["animate", "a.mcap", "a.gif"], o) for o in ("--fps", "--speed", "--dpi")] + [
    (["rosbot-emulator"], o) for o in ("--scan-beams", "--seed", "--rate", "--cmd-timeout",
                                       "--battery-voltage")
] + [(["topic", "list"], "--duration"), (["topic", "echo", "odom"], "--count"),
     (["topic", "echo", "odom"], "--timeout"), (["topic", "hz", "odom"], "--window"),
     (["topic", "hz", "odom"], "--duration"), (["topic", "pub", "cmd_vel"], "--times"),
     (["topic", "pub", "cmd_vel"], "--rate"), (["plan", "--world", "energy"], "--dt"),
     (["plan", "--world", "energy"], "--seed"), (["plan", "--world", "energy"], "--timeout"),
     (["goal", "1", "0"], "--tolerance"), (["goal", "1", "0"], "--timeout"),
     (["experiment", "crowd"], "--workers"), (["experiment", "crowd"], "--runs"),
     (["experiment", "crowd"], "--seed"), (["experiment", "crowd"], "--timeout"),
     (["experiment", "random"], "--n"), (["experiment", "energy"], "--runs"),
     (["experiment", "traffic"], "--seed"), (["run", "--world", "energy"], "--view"), (["launch", "sim"], "--view")]


@pytest.mark.parametrize("prefix,option", NUMERIC_OPTIONS)
@pytest.mark.parametrize("value", ["nan", "inf", "-inf", "1e308", "-1", "1e999"])
def test_a_non_finite_huge_or_negative_number_is_a_usage_error(prefix, option, value, capsys):
    from papf.cli import build_parser

    with pytest.raises(SystemExit) as exc:
        build_parser(prefix[0]).parse_args([*prefix, f"{option}={value}"])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and option in err and err.count("\n") == 1


# -- the viewer's WebSocket: steering only from this host ----------------------------------------
@pytest.mark.parametrize("host,goals,params,ok", [
    ("127.0.0.1", "accept", "accept", True), ("localhost", "accept", "accept", True),
    ("::1", "accept", "accept", True), ("0.0.0.0", "accept", "accept", False),
    ("0.0.0.0", "refuse", "accept", False), ("192.168.1.5", "accept", "refuse", False),
    ("robot.lan", "refuse", "refuse", True), ("0.0.0.0", "refuse", "refuse", True)])
def test_the_viewer_steers_only_from_this_host(host, goals, params, ok):
    from common.errors import ConfigError
    from nodes.viewer.__main__ import check_exposure, parse_args

    args = parse_args(["--host", host, "--goals", goals, "--params", params])
    if ok:
        check_exposure(args)
    else:
        with pytest.raises(ConfigError, match="no authentication"):
            check_exposure(args)


def test_scans_of_ever_new_lengths_keep_the_planner_memory_bounded():
    import math

    import numpy as np

    from nodes.planner.apf.strategy import APFStrategy
    from nodes.planner.core import Planner
    from schemas.messages import Goal, Odometry, Scan

    pl = Planner(APFStrategy())
    pl.set_goal(Goal(stamp_ns=1, x=5.0, y=0.0))
    for n in range(1, 300):
        scan = Scan(stamp_ns=n, angle_min=0.0, angle_increment=2 * math.pi / n, range_min=0.2,
                    range_max=10.0, ranges=np.full(n, 3.0, dtype=np.float32))
        pl.step(scan, Odometry(stamp_ns=n, x=0.0, y=0.0, yaw=0.0, v=0.0, w=0.0))
    assert len(pl._apf_for_l) <= 16


# -- a world's name names files and is printed ----------------------------------------------------
@SETTINGS
@given(st.text(max_size=120))
def test_a_world_name_that_is_taken_is_a_plain_file_name(name):
    from common.errors import WorldError
    from worlds import parse_world, world_data

    data = {**world_data("papf-test-1"), "name": name}
    try:
        world = parse_world(data, "w.toml")
    except WorldError as exc:
        assert "\x1b" not in str(exc) and "\n" not in str(exc)
        return
    assert world.name.isprintable() and "/" not in world.name and "\\" not in world.name
    assert not world.name.startswith(".") and len(world.name) <= 100


@pytest.mark.parametrize("stem", ["my world (copy)", ".hidden", "\x1b[2Jx", "a" * 300])
def test_a_default_world_name_is_the_file_stem_made_plain(stem):
    from worlds import parse_world, world_data

    data = {k: v for k, v in world_data("papf-test-1").items() if k != "name"}
    name = parse_world(data, f"/tmp/{stem}.toml").name
    assert name.isprintable() and not name.startswith(".") and 0 < len(name) <= 100


# -- files where files are expected --------------------------------------------------------------
@pytest.mark.parametrize("text,match", [("a = " + "[" * 5000 + "]" * 5000, "nested too deeply"),
                                        ("# " + "x" * (2 * 1024 * 1024), "bytes; a settings file"),
                                        ("\xff\xfe", "not a readable TOML"),
                                        ("d_o = nan", "d_o=nan")])
def test_a_hostile_params_file_is_one_line(tmp_path, text, match):
    from common.errors import ConfigError
    from nodes.planner.registry import load_params

    f = tmp_path / "p.toml"
    f.write_text(text, encoding="latin-1" if text.startswith("\xff") else "utf-8")
    with pytest.raises(ConfigError, match=match):
        load_params("papf", f)
    with pytest.raises(ConfigError, match="no such file"):
        load_params("papf", tmp_path)      # a directory where a file is expected


@pytest.mark.skipif(__import__("os").geteuid() == 0, reason="root writes anywhere")
def test_an_output_in_a_read_only_directory_is_refused_before_the_work(tmp_path):
    from common.outfiles import OutputError, check_output

    d = tmp_path / "ro"
    d.mkdir()
    d.chmod(0o555)
    try:
        with pytest.raises(OutputError, match="not writable"):
            check_output(d / "x.png")
    finally:
        d.chmod(0o755)


@pytest.mark.parametrize("what", ["profile", "map", "pub"])
def test_thousands_of_nested_brackets_are_one_line(tmp_path, what):
    from common.errors import PapfError

    deep = "[" * 5000 + "]" * 5000
    with pytest.raises(PapfError, match="nested too deeply"):
        if what == "profile":
            from papf.launch.profile import load_profile

            (tmp_path / "p.toml").write_text(f"a = {deep}\n")
            load_profile(str(tmp_path / "p.toml"))
        elif what == "map":
            from worlds.maps import load_map

            (tmp_path / "m.yaml").write_text(f"image: {deep}\n")
            load_map(tmp_path / "m.yaml")
        else:
            from papf.bus.fields import parse_value

            parse_value(deep)


def test_a_binary_launch_profile_is_one_line(tmp_path):
    from common.errors import ConfigError
    from papf.launch.profile import load_profile

    (tmp_path / "p.toml").write_bytes(b"\xff\xfe\x00\x01" * 100)
    with pytest.raises(ConfigError, match="cannot read it as UTF-8"):
        load_profile(str(tmp_path / "p.toml"))


# -- make-certs: keys and passwords never written through a planted link -------------------------
def test_make_certs_never_writes_secrets_through_a_planted_symlink(tmp_path):
    import os
    import stat

    from common.errors import ConfigError
    from papf.robot.certs import write_bundle

    out = tmp_path / "bundle"
    out.mkdir(mode=0o700)
    stolen = tmp_path / "stolen.txt"
    (out / "credentials.txt").symlink_to(stolen)          # dangling: exists() said "no bundle"
    with pytest.raises(ConfigError, match="already holds a bundle"):
        write_bundle(out, ["10.0.0.1"])
    write_bundle(out, ["10.0.0.1"], force=True)
    assert not stolen.exists() and not (out / "credentials.txt").is_symlink()
    for f in out.iterdir():
        assert stat.S_IMODE(f.stat().st_mode) & 0o077 == 0, f.name
    shared = tmp_path / "shared"
    shared.mkdir()
    os.chmod(shared, 0o777)
    with pytest.raises(ConfigError, match="every user may write in it"):
        write_bundle(shared, ["10.0.0.1"])


def test_a_key_directory_another_user_made_or_linked_is_not_used(tmp_path, monkeypatch):
    import os

    from common import runauth

    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    elsewhere = tmp_path / "attacker"
    elsewhere.mkdir()
    (tmp_path / f"papf-{os.getuid()}").symlink_to(elsewhere)
    (elsewhere / "rosbot.key").write_text("00" * 32 + " 1\n")
    with pytest.raises(runauth.KeyDirError, match="not a directory of your own"):
        runauth.publish_key("rosbot", runauth.new_key())
    assert runauth.read_key("rosbot") is None
    assert (elsewhere / "rosbot.key").read_text() == "00" * 32 + " 1\n"


def test_papf_info_shows_a_recorded_peers_escape_sequences_never_runs_them(tmp_path, capsys):
    from nodes.recorder.writer import RunWriter
    from papf.cli import main
    from schemas import Twist

    path = tmp_path / "r.mcap"
    with RunWriter(path, {"world": "\x1b]0;owned\x07", "note": "\x1b[2J" + "n" * 5000}) as w:
        w.write("rosbot/cmd_vel", Twist(stamp_ns=1, v=0.1, w=0.0).to_bytes())
        w.write("rosbot/\x1b[2J" + "k" * 100_000, b"\x80", 2)
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "\x1b" not in out and "\x07" not in out and "\\x1b[2J" in out
    assert max(len(line) for line in out.splitlines()) < 1000   # a 100 KB key: one short line


def test_the_run_summary_shows_a_reason_as_text_no_markup_no_escapes(capsys):
    from types import SimpleNamespace

    from papf.cli.run import print_summary

    result = SimpleNamespace(outcome="failed", world="energy", planner="apf", seed=0,
                             duration_s=1.0, path_length_m=1.0, charge_mAh=1.0, energy_J=1.0,
                             collisions=0, sim_time_s=1.0, wall_time_s=1.0, fleet=(),
                             min_separation_m=None,
                             reason="planner: \x1b]0;owned\x07[link=http://e]click[/link]")
    print_summary(result, "motor")
    out = capsys.readouterr().out
    assert "\x1b" not in out and "[link=http://e]click" in out
    assert "1.00 mAh (motor model)" in out          # the charge names the meter's model


@pytest.mark.parametrize("experiment", [["crowd", "--people", "0", "--runs", "1"],
                                        ["random", "--n", "1"], ["traffic"], ["paper-tests"],
                                        ["energy", "--runs", "1"], ["wang"], ["cases"]])
def test_an_experiment_out_that_is_a_file_is_one_line_before_any_run(tmp_path, capsys, experiment):
    from papf.cli import main

    f = tmp_path / "afile"
    f.write_text("mine")
    assert main(["experiment", *experiment, "--out", str(f)]) == 2
    assert "is a file" in capsys.readouterr().err and f.read_text() == "mine"


def test_safety_floor_refuses_a_csv_that_is_not_its_table_before_a_run(tmp_path, capsys):
    from papf.cli import main

    f = tmp_path / "x.csv"
    f.write_text("not,ours\n")
    assert main(["experiment", "safety-floor", "--attraction", "--out", str(f)]) == 2
    assert "not this benchmark's CSV" in capsys.readouterr().err and f.read_text() == "not,ours\n"


@SETTINGS
@given(st.text(min_size=1, max_size=300))
def test_a_namespace_taken_is_a_plain_printable_key(ns):
    from schemas import Keys

    try:
        Keys(ns)
    except ValueError:
        return
    assert ns.isprintable() and len(ns) <= 200 and "//" not in ns and not set(ns) & set("*$?# ")


def test_export_map_never_writes_through_a_dangling_link_and_checks_its_directory(tmp_path, capsys):
    from papf.cli import main

    target = tmp_path / "target.pgm"
    (tmp_path / "m.pgm").symlink_to(target)
    assert main(["export", "map", "energy", str(tmp_path / "m.yaml")]) == 2
    assert not target.exists() and "exists" in capsys.readouterr().err
    assert main(["export", "map", "energy", str(tmp_path / "no" / "m.yaml")]) == 2
    assert "does not exist" in capsys.readouterr().err


def test_a_jsonl_trace_appends_only_to_json_lines(tmp_path):
    from common.outfiles import OutputError, append_jsonl

    rec = tmp_path / "run.mcap"
    rec.write_bytes(b"\x89MCAP0\r\n" + b"\x00" * 100)
    link = tmp_path / "t.jsonl"
    link.symlink_to(tmp_path / "elsewhere.jsonl")
    for bad in (rec, link, tmp_path):
        with pytest.raises(OutputError):
            append_jsonl(bad)
    assert rec.read_bytes().startswith(b"\x89MCAP0") and not (tmp_path / "elsewhere.jsonl").exists()
    good = tmp_path / "trace.jsonl"
    for _ in range(2):
        with append_jsonl(good) as fh:
            fh.write('{"v": 1}\n')
    assert good.read_text() == '{"v": 1}\n{"v": 1}\n'


# -- the attraction sweep's reading ---------------------------------------------------------------
def test_the_attraction_sweep_reads_ceilings_and_the_tolerated_ratio():
    from papf.experiments import safety_floor as sf

    def row(planner, param, value, outcome, ratio):
        return {"world": "w", "planner": planner, "param": param, "value": f"{value:g}",
                "outcome": outcome, "ratio": ratio}

    rows = [row("apf", "k_vg", 5, "reached", 0.5), row("apf", "k_vg", 10, "reached", 1.0),
            row("apf", "k_vg", 25, "collision", 2.5), row("apf", "k_vg", 50, "reached", 5.0),
            row("apf", "v_max", 0.9, "collision", 0.5),          # not a ratio row
            row("papf", "combo", 0, "reached", 2.0)]
    sweep = {"k_vg": (("apf",), (5.0, 10.0, 25.0, 50.0))}
    assert sf.floors_of(rows, sweep) == {"k_vg": 10.0}      # stops at the first collision
    assert sf.ratio_limit(rows, ("apf", "papf")) == 2.0      # below the smallest colliding ratio
    assert sf.attraction_ratio("papf", ("k_vo_l=2.0", "k_vg=5.0")) == 2.5
    assert sf.attraction_ratio("wang", ("k_att=20.0",)) == 4.0


# -- attraction: a pull that outweighs the push is refused ---------------------------------------
@SETTINGS
@given(k_vg=st.floats(0.01, 60.0), q_g=st.floats(0.01, 12.0), k_vo_l=st.floats(1.0, 60.0),
       q_o=st.floats(-5.0, -0.2))
def test_the_attraction_ratio_has_a_measured_ceiling(k_vg, q_g, k_vo_l, q_o):
    from common.errors import ConfigError
    from nodes.planner import settings as S
    from nodes.planner.registry import load_params

    sets = [f"k_vg={k_vg!r}", f"q_g={q_g!r}", f"k_vo_l={k_vo_l!r}", f"q_o={q_o!r}"]
    ok = (k_vg <= S.K_VG_MAX and q_g <= S.Q_G_MAX and k_vo_l * abs(q_o) >= S.REPULSION_MIN
          and k_vg * q_g / (k_vo_l * abs(q_o)) <= S.ATTRACTION_RATIO_MAX)
    if ok:
        apf, _ = load_params("papf", None, sets)
        assert S.attraction_ratio(apf) <= S.ATTRACTION_RATIO_MAX
    else:
        with pytest.raises(ConfigError):
            load_params("papf", None, sets)


@pytest.mark.parametrize("planner,sets,match", [
    ("papf", ["k_vg=1000"], "k_vg=1000: must be"), ("apf", ["q_g=50"], "q_g=50: must be"),
    ("papf", ["k_vg=50", "k_vo_l=2"], "the goal's pull may be at most 5"),
    ("wang", ["k_att=1000"], "k_att=1000: must be"),
    ("wang", ["k_att=20", "k_rep_l=5"], None), ("wang", ["k_att=20", "k_rep_l=4.9"], "k_rep_l"),
    ("wang", ["control_offset_m=0.5"], "control_offset_m=0.5: must be")])
def test_attraction_settings_measured_to_collide_are_refused(planner, sets, match):
    from common.errors import ConfigError
    from nodes.planner.registry import load_params

    if match is None:
        load_params(planner, None, sets)
        return
    with pytest.raises(ConfigError, match=match):
        load_params(planner, None, sets)


def test_the_ceilings_are_the_measured_ones():
    import csv
    from pathlib import Path

    from nodes.planner import settings as S
    from nodes.planner.wang import settings as W
    from papf.experiments import safety_floor as sf

    path = Path(__file__).resolve().parents[2] / "docs" / "data" / "safety-attraction.csv"
    rows = list(csv.DictReader(path.open()))
    found = sf.floors_of(rows, sf.ATTRACTION_SWEEP)
    assert (found["k_vg"], found["q_g"], found["control_offset_m"]) == (
        S.K_VG_MAX, S.Q_G_MAX, W.CONTROL_OFFSET_MAX_M)
    wang_only = {"k_att": ((sf.WANG,), sf.ATTRACTION_SWEEP["k_att"][1])}   # wang-apf: below
    assert sf.floors_of(rows, wang_only)["k_att"] == W.K_ATT_MAX
    assert "k_att" not in found   # wang-apf, the paper's failing baseline, collides at Table 1's
    assert sf.ratio_limit(rows, (sf.APF_PAIR + (sf.ARAPF,))) == S.ATTRACTION_RATIO_MAX
    assert sf.ratio_limit(rows, (sf.WANG,)) == W.WANG_RATIO_MAX
