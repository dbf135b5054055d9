"""docs/architecture.md against the tree: every path it names exists, every package is named.

A newcomer reads the architecture page before the code; a name there that no longer exists
sends them looking for nothing. Rules the page keeps:

- a backticked path with a folder (``nodes/planner/loop.py``, ``papf/launch/``) exists;
  ``<placeholder>`` parts stand for any name (``nodes/<node>/ports.py``);
- a bare file name (``transport.py``) exists under a folder the same line names (the layer
  table's rows: ``common/`` … ``transport.py``), or, on a line naming no folder, anywhere;
- every package of the code (``common/`` … ``papf/<room>/``, ``nodes/<node>/``, as a path or as
  a module: ``nodes.recorder``) and every module of ``common/`` is named somewhere on the page.
"""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "architecture.md"
TOP = ("common", "schemas", "worlds", "nodes", "papf", "bench", "tests", "docs", ".ci")
TICKED = re.compile(r"`([^`\s]+)`")
FILE_SUFFIXES = (".py", ".toml", ".md", ".json", ".yaml")


def _lines() -> list[str]:
    return DOC.read_text(encoding="utf-8").splitlines()


def _glob(token: str) -> str:
    return re.sub(r"<[^>]+>", "*", token.rstrip("/"))


def _is_path(token: str) -> bool:
    head = token.split("/", 1)[0]
    return "/" in token and head in TOP and not token.startswith(("papf/Scan",))


def _is_bare_file(token: str) -> bool:
    return "/" not in token and token.endswith(FILE_SUFFIXES) and not token.startswith(".")


def _exists(token: str) -> bool:
    return any(ROOT.glob(_glob(token)))


def test_every_path_the_page_names_exists():
    missing = [f"line {n}: {tok}" for n, line in enumerate(_lines(), 1)
               for tok in TICKED.findall(line) if _is_path(tok) and not _exists(tok)]
    assert not missing, "docs/architecture.md names paths that do not exist: " + "; ".join(missing)


def test_every_bare_file_name_lies_under_a_folder_of_its_line():
    missing = []
    for n, line in enumerate(_lines(), 1):
        tokens = TICKED.findall(line)
        folders = [_glob(t) for t in tokens if _is_path(t) and not t.endswith(FILE_SUFFIXES)]
        for tok in filter(_is_bare_file, tokens):
            bases = [ROOT / f for f in folders] if folders else [ROOT]
            found = any(any(b.glob(f"**/{tok}")) for pattern in bases
                        for b in (pattern.parent.glob(pattern.name) if "*" in pattern.name
                                  else [pattern]))
            if not found:
                missing.append(f"line {n}: {tok} (under {', '.join(folders) or 'the tree'})")
    assert not missing, "docs/architecture.md names files that do not exist: " + "; ".join(missing)


def _packages() -> list[str]:
    out = ["common/", "schemas/", "worlds/", "bench/"]
    for parent in ("nodes", "papf"):
        out += [f"{parent}/{d.name}/" for d in sorted((ROOT / parent).iterdir())
                if d.is_dir() and (d / "__init__.py").exists()]
    return out


def test_every_package_is_named():
    text = DOC.read_text(encoding="utf-8")
    unnamed = [p for p in _packages()
               if f"`{p}" not in text and f"`{p.rstrip('/').replace('/', '.')}" not in text]
    assert not unnamed, "docs/architecture.md never names these packages: " + ", ".join(unnamed)


def test_every_common_module_is_named():
    text = DOC.read_text(encoding="utf-8")
    modules = sorted(m.name for m in (ROOT / "common").glob("*.py") if m.name != "__init__.py")
    unnamed = [m for m in modules if f"`{m}`" not in text and f"common/{m}" not in text
               and f"common.{m[:-3]}" not in text]
    assert not unnamed, "docs/architecture.md never names these modules of common/: " + \
        ", ".join(unnamed)
