"""The house plan (docs/architecture.md "Layers"): imports only point down, and no cycles.

Bottom: ``schemas``, ``common``, ``worlds``. Middle: ``nodes``, whose packages never import
one another (what two nodes share lies below them). Top: ``papf``, ``bench``.
Every import counts — module-level and function-local alike — so a lazy import cannot
hide an upward edge or a cycle. Read with :mod:`ast`, nothing is imported.
"""

from __future__ import annotations

import ast
import functools
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
LAYER = {"schemas": 0, "common": 0, "worlds": 0, "nodes": 1, "papf": 2, "bench": 2}


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def project_modules() -> dict[str, Path]:
    return {_module_name(p): p for top in LAYER for p in sorted((ROOT / top).rglob("*.py"))}


def _targets(node: ast.AST, here: str, is_pkg: bool, modules: dict[str, Path]) -> list[str]:
    """Project modules an ``import`` / ``from ... import`` statement loads."""
    if isinstance(node, ast.Import):
        names = [a.name for a in node.names]
    else:
        base = node.module or ""
        if node.level:
            pkg = here.split(".") if is_pkg else here.split(".")[:-1]
            pkg = pkg[: len(pkg) - node.level + 1]
            base = ".".join([*pkg, base] if base else pkg)
        subs = [f"{base}.{a.name}" for a in node.names]
        names = [s for s in subs if s in modules] or [base]
    out = []
    for name in names:
        while name and name not in modules:  # `import a.b.c` of a name inside a module
            name = name.rpartition(".")[0]
        if name:
            out.append(name)
    return out


@functools.cache
def _trees() -> tuple[tuple[str, Path, ast.Module], ...]:
    """Every project module's syntax tree, parsed once per test process (the checks below
    read the same files; parsing them is most of their cost)."""
    return tuple((name, path, ast.parse(path.read_text(encoding="utf-8"), str(path)))
                 for name, path in project_modules().items())


def import_graph() -> dict[str, set[str]]:
    """module -> the project modules it imports (a copy of the one graph built per process)."""
    return {name: set(edges) for name, edges in _graph().items()}


@functools.cache
def _graph() -> dict[str, frozenset[str]]:
    modules = project_modules()
    graph: dict[str, frozenset[str]] = {}
    for name, path, tree in _trees():
        edges = set()
        for node in ast.walk(tree):
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                edges.update(_targets(node, name, path.name == "__init__.py", modules))
        edges.discard(name)
        graph[name] = frozenset(edges)
    return graph


def test_imports_only_point_down():
    upward = [f"{a} -> {b}" for a, edges in import_graph().items() for b in sorted(edges)
              if LAYER[b.split(".")[0]] > LAYER[a.split(".")[0]]]
    assert not upward, "upward imports:\n" + "\n".join(upward)


def _node_of(module: str) -> str:
    """The node package of a module of nodes/: ``nodes.planner.papf.strategy`` -> ``planner``."""
    parts = module.split(".")
    return parts[1] if parts[0] == "nodes" and len(parts) > 1 else ""


def node_crossings(graph: dict[str, set[str]]) -> list[str]:
    """Imports from one node's package into another's: two processes tied by code rather
    than by the bus (docs/architecture.md "Layers")."""
    return [f"{a} -> {b}" for a, edges in graph.items() if _node_of(a)
            for b in sorted(edges) if _node_of(b) and _node_of(b) != _node_of(a)]


def test_no_node_imports_another_node():
    crossings = node_crossings(import_graph())
    assert not crossings, ("nodes importing another node (move what they share to common/, "
                           "worlds/ or schemas/):\n" + "\n".join(crossings))


def test_the_node_check_sees_a_crossing_and_not_a_sub_package():
    graph = {"nodes.lidar_sim.__main__": {"nodes.world_sim.core", "common.units"},
             "nodes.planner.papf.strategy": {"nodes.planner.core"}, "papf.cli.x": {"nodes.planner"}}
    assert node_crossings(graph) == ["nodes.lidar_sim.__main__ -> nodes.world_sim.core"]


def find_cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan, iterative)."""
    index, low, stack, on_stack, out, counter = {}, {}, [], set(), [], [0]
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = counter[0]
        counter[0] += 1
        stack.append(root)
        on_stack.add(root)
        while work:
            v, it = work[-1]
            w = next(it, None)
            if w is None:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[v])
                if low[v] == index[v]:
                    comp = []
                    while True:
                        x = stack.pop()
                        on_stack.discard(x)
                        comp.append(x)
                        if x == v:
                            break
                    if len(comp) > 1:
                        out.append(sorted(comp))
            elif w not in index:
                index[w] = low[w] = counter[0]
                counter[0] += 1
                stack.append(w)
                on_stack.add(w)
                work.append((w, iter(sorted(graph.get(w, ())))))
            elif w in on_stack:
                low[v] = min(low[v], index[w])
    return out


def test_no_import_cycles():
    cycles = find_cycles(import_graph())
    assert not cycles, "import cycles:\n" + "\n".join(" <-> ".join(c) for c in cycles)


@pytest.mark.parametrize("graph, cyclic", [
    ({"a": {"b"}, "b": {"c"}, "c": set()}, False),
    ({"a": {"b"}, "b": {"c"}, "c": {"a"}}, True),
])
def test_the_cycle_finder_finds_cycles(graph, cyclic):
    assert bool(find_cycles(graph)) == cyclic


def test_the_graph_sees_function_local_imports():
    graph = import_graph()
    assert "papf.launch.run" in graph["papf.cli.run"]        # imported inside cmd_run
    assert "nodes.base_driver.rosbot_node" in graph["nodes.base_driver.__main__"]  # lazy


# -- inside papf/: rooms by rank (docs/architecture.md "Layers") ----------------------------
# commands (cli, doctools) -> experiments -> reports -> launch, offline -> recording, bus,
# robot -> pictures (plots) -> console. Rooms of one rank do not import each other (offline
# never imports the launcher). ``papf`` itself (__init__: the version) is read by anyone.
PAPF_ROOMS = {"papf.__main__": 7, "papf.cli": 6, "papf.doctools": 6, "papf.experiments": 5,
              "papf.report": 4, "papf.launch": 3, "papf.offline": 3, "papf.recording": 2,
              "papf.bus": 2, "papf.robot": 2, "papf.link": 2, "papf.plots": 1, "papf.console": 0, "papf": -1}


def papf_room(module: str) -> str:
    """The room (folder) of a module of papf/: ``papf.offline.run`` -> ``papf.offline``."""
    return ".".join(module.split(".")[:2])


def room_violations(graph: dict[str, set[str]]) -> list[str]:
    """Edges between papf/'s rooms that do not point to a lower room (rooms of one rank,
    e.g. offline and launch, do not import each other)."""
    out = []
    for a, edges in graph.items():
        if not a.startswith("papf"):
            continue
        for b in sorted(edges):
            ra, rb = papf_room(a), papf_room(b)
            if b.startswith("papf") and ra != rb and PAPF_ROOMS[rb] >= PAPF_ROOMS[ra]:
                out.append(f"{a} -> {b}")
    return out


def test_every_papf_module_lies_in_a_room():
    loose = [m for m in project_modules() if m.startswith("papf") and papf_room(m) not in PAPF_ROOMS]
    assert not loose, f"modules outside papf/'s rooms (add the folder to PAPF_ROOMS): {loose}"


def test_papf_rooms_import_only_lower_rooms():
    bad = room_violations(import_graph())
    assert not bad, "imports across papf/'s rooms that do not point down:\n" + "\n".join(bad)


def test_the_room_check_sees_sideways_and_upward_edges():
    graph = {"papf.plots.x": {"papf.offline.run"}, "papf.offline.run": {"papf.launch.outcome"},
             "papf.cli.plan": {"papf.offline.run", "papf.plots.paths"}}
    assert room_violations(graph) == ["papf.plots.x -> papf.offline.run",
                                      "papf.offline.run -> papf.launch.outcome"]


def test_optional_imports_are_decided_once():
    """``HAVE_NUMBA`` is assigned and ``tomli`` imported only in common/optional.py."""
    places = set()
    for name, _path, tree in _trees():
        for node in ast.walk(tree):
            if isinstance(node, ast.Assign) and any(
                    isinstance(t, ast.Name) and t.id == "HAVE_NUMBA" for t in node.targets):
                places.add(name)
            if isinstance(node, ast.Import) and any(a.name == "tomli" for a in node.names):
                places.add(name)
    assert places == {"common.optional"}
