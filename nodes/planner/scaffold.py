"""``papf new planner NAME --from P``: a new planner plug-in, copied from an existing one.

Writes ``nodes/planner/NAME/`` (P's folder, its strategy renamed, ``roles = ("compared",)``)
and ``tests/unit/test_planner_NAME.py``; the registry finds the folder by itself, so
nothing else changes. Nothing is overwritten: every check runs before the first write.
Used by :mod:`papf.cli.new`.
"""

from __future__ import annotations

import ast
import importlib
import importlib.util
import keyword
import re
import subprocess
import sys
from pathlib import Path

from common.errors import ConfigError
from nodes.planner.registry import PLANNERS, car_variants

NAME_RE = re.compile(r"^[a-z][a-z0-9_]{0,31}$")
#: declarations a copy must not inherit (they would claim P's place) -> what it declares instead
OWN_DECLARATIONS = ("name", "rank", "roles", "colour", "colour_map", "car_variants")


def repo_root() -> Path:
    """The checkout this module belongs to (the folder holding ``nodes/``)."""
    return Path(__file__).resolve().parents[2]


def check_name(name: str, root: Path) -> None:
    """ConfigError (one line) unless ``name`` can be a new planner's name and folder."""
    if not NAME_RE.match(name) or keyword.iskeyword(name):
        raise ConfigError(f"planner name {name!r}: use 1-32 lowercase letters, digits or '_', "
                          "starting with a letter (it names a Python package)")
    if name in PLANNERS or name in car_variants():
        raise ConfigError(f"planner {name!r} exists already; taken: {', '.join(PLANNERS)}")
    folder = root / "nodes" / "planner"
    if (folder / name).exists() or (folder / f"{name}.py").exists():
        raise ConfigError(f"nodes/planner/{name} exists already (a module of the planner node); "
                          "choose another name")
    test = root / "tests" / "unit" / f"test_planner_{name}.py"
    if test.exists():
        raise ConfigError(f"{test.relative_to(root)} exists already; choose another name")


def class_name(name: str) -> str:
    """``my_planner`` -> ``MyPlannerStrategy``."""
    return "".join(part.capitalize() for part in name.split("_")) + "Strategy"


def _declarations(source: str, cls: str) -> tuple[int, list[tuple[int, int]]]:
    """(first line of the class body, [(start, end) lines of its own declarations]), 1-based."""
    tree = ast.parse(source)
    node = next(n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == cls)
    spans = []
    for stmt in node.body:
        targets = (stmt.targets if isinstance(stmt, ast.Assign) else
                   [stmt.target] if isinstance(stmt, ast.AnnAssign) else [])
        names = {e.id for t in targets for e in (t.elts if isinstance(t, ast.Tuple) else [t])
                 if isinstance(e, ast.Name)}
        if names & set(OWN_DECLARATIONS):
            spans.append((stmt.lineno, stmt.end_lineno))
    first = node.body[0]
    is_doc = isinstance(first, ast.Expr) and isinstance(getattr(first, "value", None), ast.Constant)
    return (first.end_lineno + 1 if is_doc else first.lineno), spans


def renamed_strategy(source: str, old_cls: str, new_cls: str, name: str) -> str:
    """``source`` with class ``old_cls`` renamed ``new_cls``, its own declarations replaced."""
    body_at, spans = _declarations(source, old_cls)
    lines = source.splitlines(keepends=True)
    drop = set()
    for start, end in spans:
        drop.update(range(start, end + 1))
        above = start - 1                   # its "#:" comment lines go with it
        while above >= 1 and lines[above - 1].strip().startswith("#"):
            drop.add(above)
            above -= 1
    own = (f'    name = "{name}"\n'
           "    rank = 100                     # after the built-in planners in every list\n"
           '    roles = ("compared",)          # in the comparison experiments (registry.ROLES)\n'
           '    colour, colour_map = "", ""    # matplotlib colour and map ("" = by index)\n')
    at = min(drop) if drop else body_at     # where P declared its name, else the body's start
    out = []
    for i, line in enumerate(lines, start=1):
        if i == at:
            out.append(own)
        if i not in drop:
            out.append(line)
    return re.sub(rf"\b{re.escape(old_cls)}\b", new_cls, "".join(out))


def plan_files(name: str, source: str, root: Path) -> dict[Path, str]:
    """Every file to write (path -> text) for planner ``name`` copied from planner ``source``."""
    if source not in PLANNERS:
        raise ConfigError(f"--from {source!r}: no such planner; valid: {', '.join(PLANNERS)}")
    cls = PLANNERS[source]
    package, module = cls.__module__.rsplit(".", 1)
    old = package.rsplit(".", 1)[1]
    folder = Path(importlib.import_module(package).__file__).parent
    new_cls = class_name(name)
    files = {}
    for path in sorted(folder.glob("*.py")):
        if path.name == "__init__.py":
            continue
        text = path.read_text(encoding="utf-8")
        if path.stem == module:
            text = renamed_strategy(text, cls.__name__, new_cls, name)
        text = text.replace(f"nodes.planner.{old}.", f"nodes.planner.{name}.")
        text = text.replace(f"nodes/planner/{old}/", f"nodes/planner/{name}/")
        files[root / "nodes" / "planner" / name / path.name] = text
    files[root / "nodes" / "planner" / name / "__init__.py"] = (
        f'"""{name}: a planner plug-in, scaffolded from {source} by ``papf new planner``.\n\n'
        ":data:`STRATEGIES` is what :mod:`nodes.planner.registry` finds here.\n\"\"\"\n\n"
        f"from nodes.planner.{name}.{module} import {new_cls}\n\nSTRATEGIES = ({new_cls},)\n")
    # a planner that reads tracks needs a road to drive on; the others reach a goal in the open
    imports, drive = ((ROAD_IMPORTS, ROAD_TEST) if cls.uses_objects else (OPEN_IMPORTS, OPEN_TEST))
    files[root / "tests" / "unit" / f"test_planner_{name}.py"] = (TEST + drive).format(
        name=name, source=source, imports=imports)
    return files


def new_planner(name: str, source: str = "apf", root: Path | None = None) -> list[Path]:
    """Scaffold planner ``name`` from ``source`` under ``root``; the files written.

    The copy drops P's claims on paper comparisons (``roles``), colours and car variants and
    declares ``roles = ("compared",)``: the new planner joins the comparison experiments.
    """
    root = root or repo_root()
    check_name(name, root)
    files = plan_files(name, source, root)
    (root / "nodes" / "planner" / name).mkdir()
    for path, text in files.items():
        with open(path, "x", encoding="utf-8") as fh:   # "x": never over an existing file
            fh.write(text)
    _sort_imports(list(files))
    return list(files)


def _sort_imports(files: list[Path]) -> None:
    """The renamed imports in the house's order (ruff's isort rule), where ruff is installed."""
    if importlib.util.find_spec("ruff") is not None:
        subprocess.run([sys.executable, "-m", "ruff", "check", "--fix", "--select", "I", "-q",
                        *map(str, files)], check=False, capture_output=True)


TEST = '''"""{name} (scaffolded from {source} by ``papf new planner``): registered, its settings
declared and in range, and it drives. Extend it with your own."""

import dataclasses

from nodes.planner.registry import PLANNERS, check_setting, make_planner, settings_of
{imports}


def test_registered_with_its_declarations():
    cls = PLANNERS["{name}"]
    assert cls.name == "{name}" and "compared" in cls.roles


def test_every_setting_declared_and_its_default_valid():
    fields = {{f.name for f in dataclasses.fields(PLANNERS["{name}"].Params)}}
    assert fields <= set(PLANNERS["{name}"].SPECS)
    for setting, (table, _, default) in settings_of("{name}").items():
        assert check_setting("{name}", setting, default, table)[1] == default
'''

OPEN_IMPORTS = "from tests.support.toysim import simulate\nfrom worlds.toy import toy_world"
ROAD_IMPORTS = "from schemas.messages import Goal, Odometry\nfrom worlds.toy import cast_scan, toy_world"

OPEN_TEST = '''

def test_reaches_the_goal_in_the_open():
    r = simulate(make_planner("{name}"), toy_world(), goal=(3.0, 1.0), max_time_s=120)
    assert r.status == "reached"
'''

ROAD_TEST = '''

def test_drives_forward_on_a_road():
    planner = make_planner("{name}")
    planner.set_goal(Goal(stamp_ns=1, x=50.0, y=2.0, tolerance=0.5, road_y_min=0.0,
                          road_lane_width=4.0, road_lanes=2))
    for k in range(3):
        t = k * 100_000_000
        cmd, _, status = planner.step(cast_scan(toy_world(), 0.1 * k, 2.0, 0.0, t),
                                      Odometry(stamp_ns=t, x=0.1 * k, y=2.0, yaw=0.0, v=0.3, w=0.0))
        assert status.state == "driving" and cmd.v > 0
'''
