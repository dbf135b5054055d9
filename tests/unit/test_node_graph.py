"""The node graph of every launch profile is closed: each input has a publisher.

A node's inputs (``nodes/<node>/ports.py``, for the options the profile starts it with)
must be published by a process of that profile, of its partner profile on the other host,
or by the launcher of whichever of the two drives the run — or come from outside the
stack: keys of the ROS 2 bridge (``bridge:``). Optional inputs (``in?``) need nothing.
"""

from __future__ import annotations

import subprocess
import sys

import pytest

from common.errors import ConfigError
from common.ports import BRIDGE, DIRECTIONS
from papf.launch.profile import (
    LAUNCHER_PORTS,
    LaunchOptions,
    load_profile,
    node_ports,
    packaged_profiles,
    resolve,
)
from schemas.keys import TOPICS

VALUES = {"world": "energy", "record": "/tmp/x.mcap", "bridge_namespace": "b"}


def processes(name: str, **values) -> dict[str, tuple]:
    """``"<profile>:<node>"`` -> declared ports of every process the profile starts."""
    prof = load_profile(name)
    graph = resolve(prof, LaunchOptions(name, connect=["tcp/h:1"], values={**VALUES, **values}))
    specs = {s.name: s.module for s in prof.nodes}
    out = {f"{name}:{p.name}": node_ports(specs[p.name], p.argv)
           for p in graph.processes if p.name != "router"}
    if prof.run:
        out[f"{name}:launcher"] = (*LAUNCHER_PORTS, ("in", prof.pose_topic, "Odometry"))
    return out


def unpublished(mine: dict, everyone: dict) -> list[str]:
    published = {key for ports in everyone.values() for d, key, _t in ports if d == "out"}
    return [f"{proc} needs {key}" for proc, ports in mine.items() for d, key, _t in ports
            if d == "in" and key not in published and not key.startswith(BRIDGE)]


@pytest.mark.parametrize("name", packaged_profiles())
def test_every_input_has_a_publisher(name):
    prof = load_profile(name)
    mine = processes(name)
    everyone = {**mine, **(processes(prof.partner) if prof.partner else {})}
    missing = unpublished(mine, everyone)
    assert not missing, f"profile {name}: inputs nobody publishes: {missing}"


@pytest.mark.parametrize("name, objects", [("sim", "truth"), ("sim", "tracker"),
                                           ("hil-laptop", "truth"), ("hil-laptop", "tracker"),
                                           ("laptop", "tracker")])
def test_obstacle_tracks_have_a_publisher(name, objects):
    prof = load_profile(name)
    mine = processes(name, objects=objects)
    everyone = {**mine, **(processes(prof.partner) if prof.partner else {})}
    assert ("in", "objects", "Objects") in mine[f"{name}:planner"]
    assert not unpublished(mine, everyone)
    publisher = "tracker" if objects == "tracker" else "lidar_sim"
    assert ("out", "objects", "Objects") in mine[f"{name}:{publisher}"]


@pytest.mark.parametrize("name", packaged_profiles())
def test_partners_and_remote_nodes_agree(name):
    prof = load_profile(name)
    if prof.partner:
        partner = load_profile(prof.partner)
        assert partner.partner == name and partner.host != prof.host
        assert set(prof.remote_nodes) <= {s.name for s in partner.nodes}
    else:
        assert not prof.remote_nodes


def test_the_check_fails_on_a_missing_publisher():
    sim = processes("sim")
    without_lidar = {k: v for k, v in sim.items() if k != "sim:lidar_sim"}
    assert unpublished(without_lidar, without_lidar) == ["sim:planner needs scan"]
    hil = processes("hil-laptop")           # the laptop half alone: no driver for odom, clock
    assert "hil-laptop:planner needs odom" in unpublished(hil, hil)


@pytest.mark.parametrize("module", ["nodes.base_driver", "nodes.world_sim", "nodes.lidar_sim", "nodes.planner",
                                    "nodes.energy_meter", "nodes.recorder", "nodes.tracker"])
def test_ports_are_well_formed_and_printed_by_help(module):
    import importlib

    decl = importlib.import_module(f"{module}.ports")
    for ports in (decl.PORTS, *decl.VARIANTS.values(), *getattr(decl, "EXTRAS", {}).values()):
        for direction, key, msg_type in ports:
            assert direction in DIRECTIONS
            if not (key.startswith(BRIDGE) or key == "**"):
                assert TOPICS[key].__name__ == msg_type, (module, key)
    text = subprocess.run([sys.executable, "-m", module, "--help"], capture_output=True,
                          text=True, timeout=60, check=True).stdout
    for _d, key, msg_type in decl.PORTS:
        assert key.removeprefix(BRIDGE) in text and msg_type in text


def test_objects_default_per_planner_and_profile():
    def objects_of(name, **values):
        graph = resolve(load_profile(name), LaunchOptions(name, connect=["tcp/h:1"],
                                                          values={**VALUES, **values}))
        return {p.name: p.argv for p in graph.processes}

    sim = objects_of("sim", planner="iapf")
    assert "--truth-objects" in sim["lidar_sim"] and "--objects" in sim["planner"]
    assert "--objects" not in objects_of("sim", planner="apf")["planner"]
    laptop = objects_of("laptop", planner="iapf")        # no ground truth on the real robot
    assert "tracker" in laptop and "--objects" in laptop["planner"]
    with pytest.raises(ConfigError, match="--objects truth is not available here; valid: none, tracker"):
        objects_of("laptop", planner="iapf", objects="truth")
