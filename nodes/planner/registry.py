"""Planner algorithms by name, and their settings (TOML file + ``--set name=value``).

Each algorithm is a strategy class with a frozen ``Params`` dataclass and
``__init__(self, params)``; :data:`PLANNERS` maps the ``--planner`` name to it.
Settings: :class:`~nodes.planner.apf.APFParams` (shared field and motion law) plus the
algorithm's own ``Params``. A TOML file may give them at top level or in ``[apf]`` /
``[<planner>]`` tables; ``--set`` takes ``name=value`` or ``table.name=value``. Every
value is checked against its declared type and range (:mod:`nodes.planner.settings`)
by :func:`check_setting`, the one check for ``--set``, ``--params`` and live parameters.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from common.errors import ConfigError
from common.params import Spec, check_all, check_value, unknown_name
from nodes.planner.apf import APFParams, apf_force
from nodes.planner.arapf import ARAPFStrategy
from nodes.planner.core import Plan, Planner, ScanView
from nodes.planner.iapf_strategy import IAPFStrategy
from nodes.planner.papf import PAPFStrategy
from nodes.planner.settings import check_strength, specs_of
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


def settings_of(planner: str) -> dict[str, tuple[str, Spec, object]]:
    """Every setting of ``planner``: name -> (table, :class:`Spec`, default value).

    ``table`` is ``"apf"`` (shared field and motion law) or the planner's name. For a
    parameter panel or any other live-parameter path: list these, and pass every new
    value through :func:`check_setting` before using it.
    """
    cls = _planner_class(planner)
    out = {}
    for table, params_cls in (("apf", APFParams), (planner, cls.Params)):
        specs = specs_of(params_cls)
        for f in dataclasses.fields(params_cls):
            out[f.name] = (table, specs[f.name], f.default)
    return out


def check_setting(planner: str, name: str, value, table: str = "") -> tuple[str, object]:
    """Validate one setting of ``planner`` -> (its table, the typed value).

    ``value`` may be text (``--set``) or typed (TOML, a live parameter). ``table`` ''
    means whichever table has the name. ConfigError in one line names the setting and
    its valid range, or the valid names (with a "did you mean") for an unknown one.
    """
    settings = settings_of(planner)
    if table not in ("", "apf", planner):
        raise ConfigError(f"setting table {table!r} is not 'apf' or {planner!r}")
    entry = settings.get(name)
    if entry is None or (table and entry[0] != table):
        raise unknown_name(name, settings, f"{planner} setting")
    return entry[0], check_value(name, value, entry[1])


def check_params(apf: APFParams, algo) -> None:
    """Every field of both parameter sets in range (the node checks what it is given)."""
    check_all(apf, specs_of(APFParams), "apf")
    check_all(algo, specs_of(type(algo)), type(algo).__name__)
    check_strength(apf, algo)


def _planner_class(planner: str) -> type:
    if planner not in PLANNERS:
        raise unknown_name(planner, PLANNERS, "planner")
    return PLANNERS[planner]


def _apply(apf: APFParams, algo, items: list[tuple[str, str, object]], planner: str):
    """Apply (table, name, value) items; table '' = whichever dataclass has the name."""
    shared = {f.name for f in dataclasses.fields(APFParams)}
    apf_vals, algo_vals = {}, {}
    for table, name, value in items:
        typed = check_setting(planner, name, value, table)[1]
        (apf_vals if name in shared else algo_vals)[name] = typed
    apf, algo = dataclasses.replace(apf, **apf_vals), dataclasses.replace(algo, **algo_vals)
    check_params(apf, algo)
    return apf, algo


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
    """(APFParams, algorithm Params) from defaults, then the preset, then ``file``, then
    ``sets``; every value checked against its declared range (:mod:`nodes.planner.settings`).

    ``preset=NAME`` (in the file or as a ``--set``; :data:`PRESETS`) selects a preset.
    """
    apf, algo = APFParams(), _planner_class(planner).Params()
    items: list[tuple[str, str, object]] = []
    if file:
        for key, value in _read_toml(file).items():
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


def _read_toml(file: str | Path) -> dict:
    path = Path(file)
    if not path.is_file():
        raise ConfigError(f"planner params {str(file)!r}: no such file")
    try:
        return tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise ConfigError(f"planner params {str(file)!r} is not a readable TOML file: "
                          f"{msg}") from None


def make_planner(planner: str, file: str | Path | None = None, sets: list[str] = ()) -> Planner:
    """A ready :class:`Planner` running the named algorithm."""
    apf, algo = load_params(planner, file, sets)
    check_params(apf, algo)   # again where the values are used (load_params checked each)
    return Planner(PLANNERS[planner](algo), apf)
