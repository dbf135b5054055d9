"""Plug-ins own their output (nodes/planner/debug.py, schemas/planner_state.py): a planner's
debug fields are declared as data, checked by the core, carried generically by
``PlannerState`` v2 with their kind, unit and style; a v1 recording still reads; nothing
outside a plug-in's folder names its fields."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import jsonschema
import msgpack
import numpy as np
import pytest

from common.errors import SchemaError
from nodes.planner.core import Plan, Planner, Strategy
from nodes.planner.debug import DebugError, DebugField, Style, check_declarations, debug_values
from nodes.planner.registry import PLANNERS, make_planner
from nodes.viewer.scene import mind_scene
from schemas.messages import BY_TYPE, DebugValue, Goal, PlannerState
from schemas.planner_state import V1_FIELDS, PlannerStateV1
from tests.support.messages import odom, planner_debug, scan

ROOT = Path(__file__).resolve().parents[2]

FIELDS = (DebugField("marks", "points", unit="m", style=Style((0.1, 0.2, 0.3, 1.0), 0.2)),
          DebugField("routes", "paths", unit="m", label="route", style=Style(dashed=True)),
          DebugField("aim", "point", unit="m"),
          DebugField("gain", "scalar", unit="1/s"),
          DebugField("tries", "count"))


def test_values_become_messages_in_declaration_order_with_kind_unit_and_style():
    out = debug_values("demo", FIELDS, {"tries": np.int64(3), "marks": np.array([[1, 2, 9]]),
                                        "routes": np.zeros((2, 3, 2)), "aim": (0.5, 0.5)})
    assert [d.name for d in out] == ["marks", "routes", "aim", "gain", "tries"]
    marks, routes, aim, gain, tries = out
    assert marks.points == ((1.0, 2.0),) and marks.colour == (0.1, 0.2, 0.3, 1.0)
    assert marks.size == 0.2 and marks.unit == "m" and marks.label == "marks"
    assert len(routes.paths) == 2 and routes.dashed and routes.label == "route"
    assert aim.points == ((0.5, 0.5),)
    assert math.isnan(gain.value) and tries.value == 3.0     # not given this cycle: empty
    state = PlannerState(stamp_ns=1, algorithm="demo", debug=out)
    assert PlannerState.from_bytes(state.to_bytes()) == state
    assert state.get("tries") == 3.0 and state.get("nope", ()) == ()


@pytest.mark.parametrize("values, says", [
    ({"quarks": [(1.0, 2.0)]}, "not declared"),
    ({"marks": [1.0, 2.0]}, "shape"),
    ({"marks": [(1.0, math.nan)]}, "non-finite"),
    ({"marks": "here"}, "not numbers"),
    ({"routes": [[(0.0, 0.0), (1.0,)]]}, "not numbers"),
    ({"aim": [(1.0, 2.0), (3.0, 4.0)]}, "shape"),
    ({"gain": [1.0]}, "scalar"),
    ({"gain": math.inf}, "infinite"),
    ({"tries": 1.5}, "count"),
    ({"tries": True}, "count"),
])
def test_an_undeclared_name_or_a_wrong_shape_is_a_clear_error(values, says):
    with pytest.raises(DebugError, match=says) as err:
        debug_values("demo", FIELDS, values)
    assert "demo" in str(err.value)


@pytest.mark.parametrize("fields, says", [
    ((DebugField("a", "blob"),), "kind"),
    ((DebugField("a", "points"), DebugField("a", "paths")), "fresh"),
    ((DebugField("Top Quarks", "points"),), "fresh"),
    ((DebugField("a", "points", style=Style((1.0, 0.0, 0.0, 2.0))),), "0..1"),
    ((DebugField("a", "points", style=Style(size=0.0)),), "size"),
    (("top_quarks",), "DebugField"),
])
def test_bad_declarations_are_refused(fields, says):
    with pytest.raises(DebugError, match=says):
        check_declarations("demo", fields)


class _Liar(Strategy):
    name = "liar"
    DEBUG = (DebugField("marks", "points"),)

    def plan(self, pos, yaw, goal, view, apf):
        return Plan(force=goal - pos, debug={"marks": [(1.0, 1.0)], "secret": 1})


def test_the_core_refuses_a_plan_with_an_undeclared_field():
    planner = Planner(_Liar())
    planner.set_goal(Goal(stamp_ns=0, x=3.0, y=0.0))
    cmd, finish = planner.command(scan(1), odom(1))
    assert cmd.v >= 0.0                      # the command is out before the debug message ...
    with pytest.raises(DebugError, match="secret"):
        finish()                             # ... which never reaches the bus wrong


def test_builtin_planners_declare_what_their_states_carry():
    assert [f.name for f in PLANNERS["papf"].DEBUG] == ["top_quarks", "abandoned_paths"]
    assert [f.name for f in PLANNERS["arapf"].DEBUG] == ["virtual_walls", "virtual_obstacles"]
    assert {f.kind for f in PLANNERS["iapf"].DEBUG} == {"count", "scalar"}
    planner = make_planner("papf")
    planner.set_goal(Goal(stamp_ns=0, x=3.0, y=0.0))
    _, state, _ = planner.step(scan(1), odom(1))
    assert [d.name for d in state.debug] == ["top_quarks", "abandoned_paths"]
    _, state, _ = make_planner("apf").step(scan(1), odom(1))
    assert state.debug == ()


@pytest.mark.parametrize("change, says", [
    ({"kind": "scalar"}, "carries its value"),
    ({"kind": "point", "points": [[0.0, 0.0], [1.0, 1.0]]}, "at most one"),
    ({"kind": "count", "points": [], "value": 1.5}, "whole number"),
    ({"colour": [0.0, 0.0, 0.0, 7.0]}, "0..1"),
    ({"kind": "blob"}, "not one of"),
])
def test_a_debug_value_of_the_wrong_form_on_the_bus_is_refused(change, says):
    good = PlannerState(stamp_ns=1, algorithm="x", debug=(
        DebugValue(name="marks", kind="points", points=((1.0, 2.0),)),))
    wire = msgpack.unpackb(good.to_bytes(), raw=False)
    wire["debug"][0].update(change)
    with pytest.raises(SchemaError, match=says):
        PlannerState.from_wire(wire)


def test_the_json_schema_names_kinds_and_units():
    schema = PlannerState.json_schema()
    assert schema["title"] == "papf/PlannerState/v2"
    item = schema["properties"]["debug"]["items"]
    assert item["properties"]["kind"]["enum"] == ["points", "paths", "point", "scalar", "count"]
    assert "unit" in item["properties"] and "colour" in item["properties"]
    state = PlannerState(stamp_ns=1, algorithm="papf", debug=planner_debug(
        "papf", top_quarks=[(1.0, 1.0)]))
    jsonschema.validate(msgpack.unpackb(state.to_bytes(), raw=False), schema)


def _v1(**kw) -> PlannerStateV1:
    return PlannerStateV1(stamp_ns=5, algorithm="papf", force=(1.0, 0.0),
                          predicted_path=((0.0, 0.0), (1.0, 0.0)), temporary_goal=(1.0, 0.0), **kw)


def test_a_v1_state_decodes_into_v2_with_its_fields_as_debug_values():
    old = _v1(top_quarks=((2.0, 1.0),), abandoned_paths=(((0.0, 0.0), (1.0, 1.0)),))
    new = BY_TYPE["papf/PlannerState/v1"].from_bytes(old.to_bytes())
    assert type(new) is PlannerState and new.TYPE == "papf/PlannerState/v2"
    assert (new.force, new.predicted_path, new.temporary_goal) == (
        old.force, old.predicted_path, old.temporary_goal)
    assert new.get("top_quarks") == ((2.0, 1.0),)
    assert new.get("abandoned_paths") == (((0.0, 0.0), (1.0, 1.0)),)
    # drawn as the plug-in draws it now: the same kinds, units and styles
    now = {d.name: d for d in planner_debug("papf", top_quarks=[(2.0, 1.0)])}
    for d in new.debug:
        assert (d.kind, d.unit, d.colour, d.size, d.dashed) == (
            now[d.name].kind, now[d.name].unit, now[d.name].colour, now[d.name].size,
            now[d.name].dashed)
    iapf = BY_TYPE[PlannerStateV1.TYPE].from_bytes(PlannerStateV1(
        stamp_ns=1, algorithm="iapf", lane_goal_y=0.75, local_minimum_count=-1).to_bytes())
    assert iapf.get("lane_goal_y") == 0.75 and iapf.get("local_minimum_count") == -1.0
    assert iapf.get("top_quarks") is None      # not its field, and empty: left out


def test_v1_fields_are_declared_by_the_planners_that_wrote_them():
    for name, (kind, unit, label, colour, size, dashed, owner) in V1_FIELDS.items():
        f = next(f for f in PLANNERS[owner].DEBUG if f.name == name)
        assert (f.kind, f.unit, f.caption, f.style.colour, f.style.size, f.style.dashed) == (
            kind, unit, label, colour, size, dashed), name


def test_a_v1_recording_reads_and_draws(tmp_path, monkeypatch):
    """A recording made before v2 (written as the recorder did then: its schema record
    ``papf/PlannerState/v1``): read back as v2 states, drawn by kind."""
    import nodes.recorder.writer as writer
    from nodes.recorder.writer import RunWriter
    from papf.plots.moment import planner_events
    from papf.recording.reader import Recording, iter_messages

    then = writer.type_for_key
    monkeypatch.setattr(writer, "type_for_key", lambda key: (
        PlannerStateV1 if key.endswith("planner/state") else then(key)))
    path = tmp_path / "v1.mcap"
    with RunWriter(path, {"world": "open", "planner": "papf"}) as w:
        w.write_message("rosbot/planner/state", _v1())
        w.write_message("rosbot/planner/state", _v1(top_quarks=((2.0, 1.0),)))
    with Recording(path) as rec:
        schemas = {s.name for s in rec.summary.schemas.values()}
    assert schemas == {"papf/PlannerState/v1"}
    states = [m for _k, m, _t in iter_messages(path, keys=["*/planner/state"])]
    assert [type(s) for s in states] == [PlannerState, PlannerState]
    assert states[1].get("top_quarks") == ((2.0, 1.0),)
    assert [e.what for e in planner_events(states)] == ["temporary goal set", "new top quark"]
    spheres = mind_scene(states[1], (0.0, 0.0))["entities"][0]["spheres"]
    assert {(sp["pose"]["position"]["x"], sp["size"]["x"]) for sp in spheres} >= {(2.0, 0.12)}


def test_nothing_outside_a_plug_in_names_its_debug_fields():
    """The recipe is true: a planner's debug names appear only in its own folder (and v1's
    history table), so a new planner's output needs no other file."""
    owners: dict[str, set[Path]] = {}     # a copy of a planner declares its fields too
    for cls in PLANNERS.values():
        for f in cls.DEBUG:
            owners.setdefault(f.name, set()).add(Path(cls.__module__.replace(".", "/")).parent)
    pattern = re.compile(r"\b(" + "|".join(map(re.escape, owners)) + r")\b")
    found = []
    for top in ("common", "schemas", "nodes", "papf", "bench", "worlds"):
        for f in (ROOT / top).rglob("*.py"):
            rel = f.relative_to(ROOT)
            if rel.as_posix() == "schemas/planner_state.py":    # v1's fields: history
                continue
            for m in pattern.finditer(f.read_text(encoding="utf-8")):
                if not any(rel.is_relative_to(o) for o in owners[m.group(1)]):
                    found.append(f"{rel}: {m.group(1)}")
    assert found == []


@dataclass(frozen=True)
class _P:
    """No settings."""


def test_a_plan_without_debug_costs_no_values():
    class Quiet(Strategy):
        name = "quiet"
        Params = _P

        def plan(self, pos, yaw, goal, view, apf):
            return Plan(force=goal - pos)

    planner = Planner(Quiet())
    planner.set_goal(Goal(stamp_ns=0, x=3.0, y=0.0))
    _, state, _ = planner.step(scan(1), odom(1))
    assert state.debug == () and state.obstacle_count == 0
