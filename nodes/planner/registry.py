"""Planner algorithms by name, and their settings (TOML file + ``--set name=value``).

Each algorithm is a strategy class with a frozen ``Params`` dataclass and
``__init__(self, params)``; :data:`PLANNERS` maps the ``--planner`` name to it.
Settings: :class:`~nodes.planner.apf.APFParams` (shared field and motion law) plus the
algorithm's own ``Params``. A TOML file may give them at top level or in ``[apf]`` /
``[<planner>]`` tables; ``--set`` takes ``name=value`` or ``table.name=value``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from common.errors import ConfigError
from nodes.planner.apf import APFParams, apf_force
from nodes.planner.arapf import ARAPFStrategy
from nodes.planner.core import Plan, Planner, ScanView
from nodes.planner.iapf_strategy import IAPFStrategy
from nodes.planner.papf import PAPFStrategy
from nodes.planner.wang import WangAPFStrategy, WangStrategy

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib  # type: ignore[no-redef]


PRESETS = ("default", "paper")


class APFStrategy:
    """Classic APF (PAPF paper eq. 2): steer by the resultant force towards the global goal."""

    name = "apf"
    PAPER_PRESET: dict = {}   # eq. 2 as written already: no deviation to switch off

    @dataclass(frozen=True)
    class Params:
        """Classic APF has no settings beyond :class:`APFParams`."""

    def __init__(self, params: Params | None = None):
        self.params = params or self.Params()

    def reset(self) -> None:
        pass

    def plan(self, pos: np.ndarray, yaw: float, goal: np.ndarray, view: ScanView,
             apf: APFParams) -> Plan:
        return Plan(force=apf_force(pos, goal, view.points, apf))


PLANNERS: dict[str, type] = {
    "apf": APFStrategy,
    "papf": PAPFStrategy,
    "arapf": ARAPFStrategy,
    "wang": WangStrategy,
    "wang-apf": WangAPFStrategy,
    "iapf": IAPFStrategy,
}


def _convert(cls, name: str, text):
    """Parse ``text`` to the type of ``cls.name``; ConfigError names the field and type."""
    f = {f.name: f for f in dataclasses.fields(cls)}[name]
    kind = type(f.default)
    if not isinstance(text, str):
        value = text
    elif kind is bool:
        low = text.strip().lower()
        if low not in ("true", "false", "1", "0", "yes", "no"):
            raise ConfigError(f"setting {name}={text!r}: expected true or false")
        value = low in ("true", "1", "yes")
    else:
        try:
            value = kind(text)
        except ValueError:
            raise ConfigError(f"setting {name}={text!r}: expected a {kind.__name__}") from None
    if kind is float and isinstance(value, int) and not isinstance(value, bool):
        value = float(value)
    if not isinstance(value, kind):
        raise ConfigError(f"setting {name}={value!r}: expected a {kind.__name__}")
    return value


def _apply(apf: APFParams, algo, items: list[tuple[str, str, object]], planner: str):
    """Apply (table, name, value) items; table '' = whichever dataclass has the name."""
    apf_vals, algo_vals = {}, {}
    apf_names = {f.name for f in dataclasses.fields(apf)}
    algo_names = {f.name for f in dataclasses.fields(algo)}
    for table, name, value in items:
        if table not in ("", "apf", planner):
            raise ConfigError(f"setting table {table!r} is not 'apf' or {planner!r}")
        if name in algo_names and table in ("", planner):
            algo_vals[name] = _convert(type(algo), name, value)
        elif name in apf_names and table in ("", "apf"):
            apf_vals[name] = _convert(APFParams, name, value)
        else:
            valid = sorted(apf_names | algo_names)
            raise ConfigError(f"unknown planner setting {name!r} for {planner!r}; valid: {valid}")
    return dataclasses.replace(apf, **apf_vals), dataclasses.replace(algo, **algo_vals)


def preset_settings(planner: str, preset: str) -> dict:
    """The settings a preset makes: ``default`` none, ``paper`` the strategy's ``PAPER_PRESET``
    (the paper read literally, every deviation of ours off; docs/planners.md, "Presets")."""
    if preset not in PRESETS:
        raise ConfigError(f"unknown preset {preset!r}; valid: {list(PRESETS)}")
    return dict(getattr(PLANNERS[planner], "PAPER_PRESET", {})) if preset == "paper" else {}


def preset_sets(preset: str) -> list[str]:
    """``--preset NAME`` as ``--set`` strings (none for ``default``, so a file's preset stands)."""
    if preset not in PRESETS:
        raise ConfigError(f"unknown preset {preset!r}; valid: {list(PRESETS)}")
    return [] if preset == "default" else [f"preset={preset}"]


def _with_preset(planner: str, items: list[tuple[str, str, object]]):
    """Resolve the reserved setting ``preset`` (last one wins): its settings go first, so a
    file or ``--set`` can still switch a single deviation back."""
    chosen = [str(v).strip() for t, n, v in items if n == "preset" and t in ("", planner)]
    rest = [it for it in items if not (it[1] == "preset" and it[0] in ("", planner))]
    if not chosen:
        return rest
    return [("", k, v) for k, v in preset_settings(planner, chosen[-1]).items()] + rest


def load_params(planner: str, file: str | Path | None = None, sets: list[str] = ()):
    """(APFParams, algorithm Params) from defaults, then the preset, then ``file``, then ``sets``.

    ``preset=NAME`` (in the file or as a ``--set``; :data:`PRESETS`) selects a preset.
    """
    if planner not in PLANNERS:
        raise ConfigError(f"unknown planner {planner!r}; valid: {sorted(PLANNERS)}")
    apf, algo = APFParams(), PLANNERS[planner].Params()
    items: list[tuple[str, str, object]] = []
    if file:
        try:
            data = tomllib.loads(Path(file).read_text())
        except (OSError, tomllib.TOMLDecodeError) as exc:
            raise ConfigError(f"cannot read planner params {str(file)!r}: {exc}") from None
        for key, value in data.items():
            if isinstance(value, dict):
                if key not in ("apf", planner):  # tables of other planners are ignored
                    continue
                items += [(key, k, v) for k, v in value.items()]
            else:
                items.append(("", key, value))
    for text in sets:
        if "=" not in text:
            raise ConfigError(f"--set {text!r}: expected name=value")
        key, value = text.split("=", 1)
        table, _, name = key.strip().rpartition(".")
        items.append((table, name, value.strip()))
    return _apply(apf, algo, _with_preset(planner, items), planner)


def make_planner(planner: str, file: str | Path | None = None, sets: list[str] = ()) -> Planner:
    """A ready :class:`Planner` running the named algorithm."""
    apf, algo = load_params(planner, file, sets)
    return Planner(PLANNERS[planner](algo), apf)
