"""`papf launch`: the packaged profiles, their plans and errors, dry runs."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from common.errors import ConfigError
from papf.launch.profile import (
    LaunchOptions,
    load_profile,
    local_endpoint,
    packaged_profiles,
    resolve,
)
from tests.support.worlds import FAST, SHORT, write_world

PY = sys.executable


@pytest.fixture
def world(tmp_path) -> str:
    return str(write_world(tmp_path / "short.toml", SHORT))


def plan(prof, opt):
    graph = resolve(prof, opt)
    return graph.nodes, graph.connect


# -- profiles as data ---------------------------------------------------------------------------
def test_packaged_profiles_load():
    assert {"sim", "robot", "laptop", "hil-robot", "hil-laptop"} <= set(packaged_profiles())
    for name in packaged_profiles():
        prof = load_profile(name)
        assert prof.nodes and prof.name == name
        assert prof.router or prof.run                 # a host either serves or drives
    assert [load_profile(n).router for n in ("robot", "hil-robot", "laptop", "hil-laptop")] == \
        [True, True, False, False]


def test_robot_profile_plan():
    prof = load_profile("robot")
    cmds, connect = plan(prof, LaunchOptions("robot", values={"bridge_namespace": "r1"}))
    assert list(cmds) == ["base_driver", "lidar_sim"] and connect == ["tcp/127.0.0.1:7447"]
    drv = cmds["base_driver"]
    assert drv[1:3] == ["-m", "nodes.base_driver"] and "--world" not in drv
    assert drv[drv.index("--driver") + 1] == "rosbot" and "--realtime" in drv
    assert drv[drv.index("--bridge-namespace") + 1] == "r1"
    assert cmds["lidar_sim"][cmds["lidar_sim"].index("--source") + 1] == "ros2"
    cmds, _ = plan(prof, LaunchOptions("robot", values={"world": "open"}))
    assert cmds["base_driver"][cmds["base_driver"].index("--world") + 1].endswith("open.toml")


def test_laptop_profile_plan_and_errors(world):
    prof = load_profile("laptop")
    opt = LaunchOptions("laptop", connect=["tcp/10.0.0.2:7447"], namespace="r7",
                        values={"world": world, "record": "/tmp/x.mcap"}, planner_args=FAST)
    cmds, connect = plan(prof, opt)
    assert list(cmds) == ["recorder", "energy_meter", "planner"] and connect == opt.connect
    assert cmds["planner"][-4:] == ["--connect", "tcp/10.0.0.2:7447", "--namespace", "r7"]
    assert "--realtime" in cmds["planner"] and "v_max=0.5" in cmds["planner"]
    assert cmds["energy_meter"][cmds["energy_meter"].index("--model") + 1] == "motor"   # one model everywhere
    assert "recorder" not in plan(prof, LaunchOptions("laptop", connect=["tcp/h:1"]))[0]
    with pytest.raises(ConfigError, match="give --connect"):
        plan(prof, LaunchOptions("laptop"))
    with pytest.raises(ConfigError, match="needs --world"):
        plan(load_profile("hil-laptop"), LaunchOptions("hil-laptop", connect=["tcp/h:1"]))
    with pytest.raises(ConfigError, match="no launch profile 'nope'"):
        load_profile("nope")


def test_bad_profile_file(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('name = "bad"\n[[nodes]]\nmodule = "x"\n')
    with pytest.raises(ConfigError, match="invalid: KeyError"):
        load_profile(str(bad))
    bad.write_text('router = true\n[[nodes]]\nname = "a"\nmodule = "x"\n')
    with pytest.raises(ConfigError, match="needs listen endpoints"):
        load_profile(str(bad))


def test_local_endpoint():
    assert local_endpoint("tcp/0.0.0.0:7447") == "tcp/127.0.0.1:7447"
    assert local_endpoint("tcp/[::]:7447") == "tcp/127.0.0.1:7447"
    assert local_endpoint("tcp/10.231.0.1:7447") == "tcp/10.231.0.1:7447"


def test_dry_run_prints_the_process_list():
    out = json.loads(subprocess.run([PY, "-m", "papf", "launch", "hil-robot", "--dry-run",
                                     "--listen", "tcp/127.0.0.1:1"], capture_output=True,
                                    text=True, timeout=60, check=True).stdout)
    router, driver = out["processes"]
    assert out["profile"] == "hil-robot" and router["host"] == driver["host"] == "robot"
    assert router["argv"][1:] == ["-m", "papf.launch.router", "--listen", "tcp/127.0.0.1:1"]
    assert driver["argv"][1:5] == ["-m", "nodes.base_driver", "--driver", "rosbot"]


def test_papf_run_and_launch_sim_dry_runs_print_the_same_processes(tmp_path):
    args = ["--world", "energy", "--planner", "papf", "--seed", "3", "--set", "v_max=0.2",
            "--record", str(tmp_path / "r.mcap"), "--energy-model", "paper"]
    run = subprocess.run([PY, "-m", "papf", "run", *args, "--dry-run"], capture_output=True,
                         text=True, timeout=60, check=True).stdout
    launch = subprocess.run([PY, "-m", "papf", "launch", "sim", *args, "--dry-run"],
                            capture_output=True, text=True, timeout=60, check=True).stdout
    assert run == launch
    procs = {p["name"]: p["argv"] for p in json.loads(run)["processes"]}
    assert list(procs) == ["router", "recorder", "energy_meter", "planner", "lidar_sim",
                           "base_driver"]
    rec = procs["recorder"]
    meta = dict(rec[i + 1].split("=", 1) for i, a in enumerate(rec) if a == "--meta")
    assert meta == {"profile": "sim", "world": "energy", "planner": "papf", "seed": "3",
                    "planner_args": "--set v_max=0.2", "energy_model": "paper", "timeout_s": "300"}
