"""Issue 20, items 5, 6, 8, 9, 11, 12: worlds taken on trust, one preflight for run and
launch, nodes that import from the caller's directory, the replay guard's namespaces,
experiments that keep finished runs, and the smaller holes. Property-based where the input
space is open (keys, text)."""

from __future__ import annotations

import json
import math
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from common.errors import ConfigError, WorldError
from papf.bus.decode import as_text, safe_text
from papf.cli.report import finite
from papf.experiments.journal import Journal, run_key
from papf.launch.preflight import check_launch
from papf.launch.profile import LaunchOptions, load_profile
from papf.launch.supervisor import _SAFE_BOOT, safe_argv
from worlds import load_world, parse_world, world_data, world_path
from worlds.kinds import KINDS
from worlds.validate import MAX_LANES, MAX_OBSTACLES, MAX_TRACK_POINTS, TOP

SETTINGS = settings(max_examples=40, deadline=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture])
BASE = world_data("energy-blocking")


def _with(**top) -> dict:
    return {**json.loads(json.dumps(BASE)), **top}


@SETTINGS
@given(key=st.text(st.characters(min_codepoint=97, max_codepoint=122), min_size=1, max_size=12))
def test_any_unknown_obstacle_key_is_refused(key):
    data = _with()
    ob = data["obstacles"][1]   # a cylinder
    if key in ("kind", *KINDS["cylinder"].keys):
        return
    ob[key] = 2.0
    with pytest.raises(WorldError, match=r"obstacles\[1\]\." + key + ": unknown key"):
        parse_world(data, "w.toml")


@pytest.mark.parametrize("data,match", [
    ({"hieght": 2.0}, "did you mean 'height'"),
])
def test_a_misspelt_key_says_what_was_meant(data, match):
    world = _with()
    world["obstacles"][1].update(data)
    with pytest.raises(WorldError, match=match):
        parse_world(world, "w.toml")


@SETTINGS
@given(table=st.text(st.characters(min_codepoint=97, max_codepoint=122), min_size=1, max_size=10))
def test_any_unknown_table_is_refused(table):
    if table in TOP:
        return
    with pytest.raises(WorldError, match="unknown key"):
        parse_world(_with(**{table: {"x": 1}}), "w.toml")


@pytest.mark.parametrize("extra,match", [
    ({"road": {"y_min": -1.0, "lane_width": 1.0, "lanes": 10**9}}, f"more than {MAX_LANES}"),
    ({"name": "x" * 1000}, "characters, more than"),
    ({"obstacles": [{"kind": "box", "size": [0.1, 0.1],
                     "motion": {"track": [[float(t), 5.0, 5.0] for t in range(MAX_TRACK_POINTS + 1)]}}]},
     "points, more than"),
])
def test_sizes_a_world_may_ask_for_are_bounded(extra, match):
    with pytest.raises(WorldError, match=match):
        parse_world(_with(**extra), "w.toml")


@pytest.mark.parametrize("text,match", [
    ("a = " + "[" * 50_000 + "]" * 50_000 + "\n", "nested too deeply"),
    ('name = "' + "x" * 2_000_000 + '"\n', "more than the 1,048,576"),
    ("a = " + "[" * 10 + "]" * 10 + "\n", "nested deeper than"),
])
def test_hostile_files_fail_fast_in_one_line(tmp_path, text, match):
    f = tmp_path / "w.toml"
    f.write_text(text)
    t0 = time.monotonic()
    with pytest.raises(WorldError, match=match) as exc:
        load_world(f)
    assert time.monotonic() - t0 < 10 and "\n" not in str(exc.value)


def test_a_huge_world_argument_is_one_line():
    with pytest.raises(WorldError, match="at most 4,096"):
        load_world("x" * 50_000)


def _launch(**kw):

    values = {"world": "energy", **kw.pop("values", {})}
    return LaunchOptions(kw.pop("profile", "sim"), values=values, **kw)


@pytest.mark.parametrize("opt,match", [
    (_launch(timeout_s=math.nan), "--timeout=nan"),
    (_launch(namespace="a//b"), "--namespace"),
    (_launch(listen=["tcp/127.0.0.1:99999"]), "port '99999'"),
    (_launch(listen=["tcp/[::1"]), "must look like"),
    (_launch(values={"seed": -1}), "--seed=-1"),
    (_launch(planner_args=["--set", "d_o=nan"]), "d_o=nan"),
    (_launch(values={"planner": "papff"}), "did you mean 'papf'"),
    (_launch(values={"world": "wang-3d-fig9"}), "3-D"),
])
def test_launch_makes_the_checks_run_makes(opt, match):
    with pytest.raises((ConfigError, WorldError), match=match):
        check_launch(opt, load_profile("sim"))


def test_launch_refuses_worlds_run_refuses(tmp_path):
    head = '[goal]\nposition = [{gx}, {gy}]\n'
    many = head.format(gx=10.0, gy=0.0) + "".join(
        f'[[obstacles]]\nkind = "cylinder"\ncenter = [{20.0 + i * 0.3}, 20.0]\nradius = 0.1\n'
        for i in range(MAX_OBSTACLES + 1))
    inside = head.format(gx=5.0, gy=0.0) + \
        '[[obstacles]]\nkind = "cylinder"\ncenter = [5.0, 0.0]\nradius = 0.25\n'
    for text, match in ((many, "obstacles"), (inside, "goal")):
        f = tmp_path / "w.toml"
        f.write_text(text)
        with pytest.raises(WorldError, match=match):
            check_launch(_launch(values={"world": str(f)}), load_profile("sim"))


def test_launch_refuses_an_existing_recording_unless_forced(tmp_path):
    rec = tmp_path / "a.mcap"
    rec.write_bytes(b"user's")
    with pytest.raises(ConfigError, match="already exists"):
        check_launch(_launch(values={"record": str(rec)}), load_profile("sim"))
    check_launch(_launch(values={"record": str(rec), "record_force": "1"}), load_profile("sim"))


def _shadow(tmp_path: Path) -> Path:
    (tmp_path / "worlds").mkdir()
    (tmp_path / "worlds" / "__init__.py").write_text("")
    (tmp_path / "common").mkdir()
    (tmp_path / "common" / "__init__.py").write_text("raise SystemExit('shadowed')\n")
    return tmp_path


def test_nodes_started_from_a_directory_with_our_package_names_import_ours(tmp_path):
    import os

    cwd = _shadow(tmp_path)
    argv = safe_argv([sys.executable, "-m", "nodes.recorder", "--help"])
    env = {**os.environ, "PYTHONSAFEPATH": "1"}
    p = subprocess.run(argv, cwd=cwd, env=env, capture_output=True, text=True, timeout=120)
    assert p.returncode == 0 and "shadowed" not in p.stdout + p.stderr
    boot = [sys.executable, "-c", _SAFE_BOOT, "nodes.recorder", "--help"]   # the 3.10 path
    p = subprocess.run(boot, cwd=cwd, capture_output=True, text=True, timeout=120)
    assert p.returncode == 0 and "usage: python -m nodes.recorder" in p.stdout


def test_the_replay_guard_takes_the_namespaces_of_the_keys(tmp_path):
    from nodes.recorder.writer import RunWriter
    from papf.recording.reader import Recording
    from papf.recording.replay import target_namespaces
    from schemas import Twist

    path = tmp_path / "r.mcap"
    with RunWriter(path, {"namespace": "elsewhere"}) as w:
        w.write_message("rosbot/cmd_vel", Twist(stamp_ns=1, v=0.1, w=0.0))
        w.write_message("lab/r1/scan", Twist(stamp_ns=2, v=0.0, w=0.0))
    with Recording(path) as rec:
        assert target_namespaces(rec) == {"rosbot", "lab/r1"}
        assert target_namespaces(rec, namespace="elsewhere") == {"rosbot", "lab/r1"}
        assert target_namespaces(rec, namespace="x") == {"rosbot", "lab/r1"}


@SETTINGS
@given(entries=st.dictionaries(st.text(max_size=8), st.floats(allow_nan=True), max_size=5))
def test_the_journal_gives_back_what_it_took_and_ignores_garbage(tmp_path_factory, entries):
    out = tmp_path_factory.mktemp("exp")
    j = Journal(out)
    key = run_key("world", "apf", 1)
    assert j.get(key) is None
    j.put(key, {"x": finite(entries)})
    assert Journal(out).get(key) == {"x": finite(entries)}
    (j.dir / f"{key}.json").write_text("{not json")
    assert Journal(out).get(key) is None
    (j.dir / f"{key}.json").write_text(json.dumps({"key": "other", "data": {}}))
    assert Journal(out).get(key) is None


def test_a_sweep_keeps_each_run_as_it_ends_and_resumes(tmp_path, monkeypatch):
    from papf.experiments import trials

    world = load_world("open")
    jobs = [trials.trial_job(world, world_path("open"), planner="apf", seed=s, mode="offline",
                             timeout_s=1.0, index=s) for s in range(3)]
    made = []

    def fake_run(job):
        made.append(job.seed)
        if job.seed == 2 and len(made) == 3:
            raise KeyboardInterrupt   # Ctrl-C during the third run
        return trials.Trial(job.world.name, job.planner, job.seed, "offline", "reached", 1.5,
                            2.0, 0, path=np.array([[0.0, 0.0], [1.0, 0.5]])), None

    monkeypatch.setattr(trials, "run_job", fake_run)
    with pytest.raises(KeyboardInterrupt):
        trials.sweep_trials(jobs, None, False, "t", tmp_path)
    assert len(list((tmp_path / "runs").glob("*.json"))) == 2
    done = trials.sweep_trials(jobs, None, False, "t", tmp_path)
    assert made == [0, 1, 2, 2] and [t.seed for t in done] == [0, 1, 2]
    assert done[0].path.tolist() == [[0.0, 0.0], [1.0, 0.5]] and math.isnan(done[0].charge_mAh)


@SETTINGS
@given(st.text(max_size=400))
def test_echoed_text_has_no_control_characters_and_is_bounded(text):
    shown = safe_text(text)
    assert shown.isprintable() and len(shown) <= 200 * 10 + 40
    line = as_text({"k\x1b": text})
    assert "\x1b" not in line and "\x07" not in line


def test_report_json_has_no_nan():
    assert json.dumps(finite({"a": math.nan, "b": [math.inf, 1.0]}), allow_nan=False) == \
        '{"a": null, "b": [null, 1.0]}'
