"""docs/architecture.md "Extending" against the tree and the registries: every listed path
exists (``<name>``/``<n>`` for the recipe's model), each count matches its list, the planner
declarations and roles are those of ``Strategy`` and the registry, and the obstacle-kind
list is every file that branches on a shape."""

import re
import typing
from pathlib import Path

import pytest

from nodes.planner import registry
from nodes.planner.core import Strategy

ROOT = Path(__file__).resolve().parents[2]
DOC = (ROOT / "docs" / "architecture.md").read_text(encoding="utf-8")
# a comparison with an obstacle kind's name, or with an obstacle's shape
SHAPE = re.compile(r'(shape|kind)\s*(==|!=|in)\s*\(?"(box|cylinder|sphere|wall|map)"|\.shape\s*(==|!=|in)\s')


def section() -> str:
    return DOC.split("\n## Extending\n", 1)[1].split("\n## ", 1)[0]


def recipes() -> dict[str, str]:
    """``### title`` -> its text."""
    parts = re.split(r"\n### (.+)\n", "\n" + section())
    return dict(zip(parts[1::2], parts[2::2], strict=True))


def bullets(text: str) -> list[list[str]]:
    """The backticked paths of each ``- `path` — ...`` bullet (before the dash)."""
    out = []
    for line in text.splitlines():
        if line.startswith("- `"):
            head = line.split(" — ", 1)[0]
            out.append(re.findall(r"`([^`]+)`", head))
    return out


def table(text: str, after: str) -> list[str]:
    """First column (backticked) of the table following the line starting with ``after``."""
    block = text.split(after, 1)[1].split("\n\n", 2)[1]
    return re.findall(r"^\| `([^`]+)` \|", block, flags=re.M)


def model(text: str) -> dict[str, str]:
    """``(`<name>` = x)`` -> {"<name>": "x"}."""
    return dict(re.findall(r"\(`(<[a-z]+>)` = ([a-z0-9_]+)\)", text))


def planner_folders() -> list[str]:
    return sorted({cls.__module__.split(".")[2] for cls in registry.PLANNERS.values()})


def test_every_recipe_is_there():
    assert set(recipes()) == {"A planner", "A node", "An obstacle kind", "A message",
                              "An experiment"}


@pytest.mark.parametrize("title", ["A planner", "A node", "An obstacle kind", "A message",
                                   "An experiment"])
def test_listed_paths_exist_and_count_matches(title):
    text = recipes()[title]
    listed = bullets(text)
    count = int(re.search(r"Files to touch: (\d+)\.", text).group(1))
    assert len(listed) == count
    names = model(text)
    for paths in listed:
        for path in paths:
            if "<name>" in path and title == "A planner":
                for folder in planner_folders():   # every plug-in has the layout
                    assert (ROOT / path.replace("<name>", folder)).exists(), (path, folder)
                continue
            for key, value in names.items():
                path = path.replace(key, value)
            assert "<" not in path and (ROOT / path).exists(), path


def test_planner_declarations_are_the_strategy_s():
    text = recipes()["A planner"]
    declared = table(text, "What a strategy declares")
    hooks = {"reset", "observe", "warm_up", "plan", "check_strength"}
    own = [n for n in vars(Strategy) if not n.startswith("_") and n not in hooks]
    assert sorted(declared) == sorted(own)
    hints = typing.get_type_hints(Strategy)
    assert set(declared) <= set(hints)


def test_roles_are_the_registry_s():
    assert table(recipes()["A planner"], "Roles (") == list(registry.ROLES)


def test_nothing_outside_the_kinds_branches_on_a_kind():
    """The obstacle-kind recipe is true: no file outside ``worlds/kinds/`` asks which kind an
    obstacle is (a new kind changes only the files the recipe lists)."""
    found = sorted(str(f.relative_to(ROOT)) for top in ("common", "schemas", "worlds", "nodes", "papf")
                   for f in (ROOT / top).rglob("*.py")
                   if "kinds" not in f.parts and SHAPE.search(f.read_text(encoding="utf-8")))
    assert found == []
    assert {p for paths in bullets(recipes()["An obstacle kind"]) for p in paths} >= {
        "worlds/kinds/<kind>.py", "worlds/kinds/__init__.py"}
