"""Planner plug-ins by name, and their settings (TOML file + ``--set name=value``).

The one list of planners: every package under ``nodes/planner/`` that exports
``STRATEGIES``, ordered by ``rank`` (:data:`PLANNERS`). What the rest of the house needs
to know about planners (CLI choices, colours, experiments' lists, ...) is derived here
(:func:`with_role`, :func:`declared`, :func:`car_variants`); settings are checked by
:func:`check_setting`, the one check for ``--set``, ``--params`` and live parameters.
Used by the planner node, ``papf run``/``plan``/``new`` and the experiments.
"""

from __future__ import annotations

import dataclasses
import importlib
import pkgutil
from pathlib import Path

import nodes.planner as planner_package
from common.errors import ConfigError
from common.optional import tomllib
from common.params import Spec, check_all, check_value, unknown_name
from common.syntax import toml_problem
from nodes.planner.core import NoParams, Planner, Strategy
from nodes.planner.debug import check_declarations
from nodes.planner.field import APFParams
from nodes.planner.settings import APF as APF_SPECS
from nodes.planner.settings import check_strength

PRESETS = ("default", "paper")


#: the parts a planner may declare it plays (``Strategy.roles``): ``compared`` puts it in the
#: comparison experiments' default planner lists, ``traffic`` in the traffic experiment's
#: (beside the planners that read tracks), ``crowd`` in the crowd experiment's; ``<paper>-baseline`` /
#: ``<paper>-proposed`` name the planner a paper's own comparison is about (at most one planner each).
ROLES = ("compared", "traffic", "crowd", "papf-baseline", "papf-proposed", "arapf-proposed",
         "wang-proposed", "wang-baseline", "car-proposed")


def _discover() -> dict[str, type[Strategy]]:
    """Every plug-in's strategies, by (rank, name): the packages of nodes/planner/ with ``STRATEGIES``."""
    found: list[type[Strategy]] = []
    for info in sorted(pkgutil.iter_modules(planner_package.__path__), key=lambda i: i.name):
        if info.ispkg:
            found += importlib.import_module(f"{planner_package.__name__}.{info.name}").__dict__.get(
                "STRATEGIES", ())
    found.sort(key=lambda c: (c.rank, c.name))
    out: dict[str, type[Strategy]] = {}
    for cls in found:
        if not (isinstance(cls, type) and issubclass(cls, Strategy)) or not cls.name:
            raise TypeError(f"{cls!r}: a planner must be a named nodes.planner.core.Strategy")
        if cls.name in out:
            raise TypeError(f"planner name {cls.name!r} declared twice ({out[cls.name]}, {cls})")
        unknown = set(cls.roles) - set(ROLES)
        if unknown:
            raise TypeError(f"planner {cls.name!r}: unknown roles {sorted(unknown)}; valid: {ROLES}")
        check_declarations(cls.name, cls.DEBUG)    # its debug output, declared as data
        out[cls.name] = cls
    return out


PLANNERS: dict[str, type[Strategy]] = _discover()
DEFAULT_PLANNER = next(iter(PLANNERS))   # the first by rank: classic APF


def with_role(role: str) -> tuple[str, ...]:
    """The planners that declare ``role`` (:data:`ROLES`), in registry order."""
    if role not in ROLES:
        raise ValueError(f"unknown role {role!r}; valid: {ROLES}")
    return tuple(name for name, cls in PLANNERS.items() if role in cls.roles)


def one_with_role(role: str) -> str:
    """The one planner a paper's comparison is about (e.g. ``papf-proposed``)."""
    names = with_role(role)
    if len(names) != 1:
        raise LookupError(f"role {role!r}: expected one planner, found {list(names)}")
    return names[0]


def declared(attr: str) -> dict[str, object]:
    """``name -> value`` of one declaration (``colour``, ``uses_objects``, ...), where set."""
    return {name: getattr(cls, attr) for name, cls in PLANNERS.items() if getattr(cls, attr)}


def car_variants() -> dict[str, tuple[str, str, dict, str]]:
    """Car-scale run name -> (planner, label, settings changed, colour) (``Strategy.car_variants``)."""
    return {variant: (name, label, dict(changes), colour) for name, cls in PLANNERS.items()
            for variant, (label, changes, colour) in cls.car_variants.items()}


def specs_of(params_cls: type) -> dict[str, Spec]:
    """The declared specs of a params class (the shared APF table or a strategy's ``SPECS``)."""
    if params_cls is APFParams:
        return APF_SPECS
    for cls in PLANNERS.values():
        if cls.Params is params_cls:
            return cls.SPECS
    return {}


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
    check_strength(apf)
    for cls in PLANNERS.values():
        if isinstance(algo, cls.Params) and cls.Params is not NoParams:
            cls.check_strength(apf, algo)


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
    return dict(_planner_class(planner).PAPER_PRESET) if preset == "paper" else {}


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

    Settings: :class:`~nodes.planner.field.APFParams` (shared field and motion law) plus the
    algorithm's own ``Params``. A TOML file may give them at top level or in ``[apf]`` /
    ``[<planner>]`` tables; ``--set`` takes ``name=value`` or ``table.name=value``. Every
    value is checked against its declared type and range (the strategy's ``SPECS``).
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


MAX_PARAMS_BYTES = 1024 * 1024   # [bytes] a --params file (as a world file: worlds/validate.py)


def _read_toml(file: str | Path) -> dict:
    path = Path(file)
    if not path.is_file():
        raise ConfigError(f"planner params {str(file)!r}: no such file")
    try:
        size = path.stat().st_size
        if size > MAX_PARAMS_BYTES:   # a settings file is a few hundred bytes
            raise ConfigError(f"planner params {str(file)!r}: {size:,} bytes; a settings file "
                              f"has at most {MAX_PARAMS_BYTES:,}")
        text = path.read_text(encoding="utf-8")
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"planner params {str(file)!r} is not valid TOML: "
                          f"{toml_problem(exc, text)}") from None
    except RecursionError:   # tomllib on thousands of nested arrays or tables
        raise ConfigError(f"planner params {str(file)!r}: nested too deeply to be "
                          "settings") from None
    except (OSError, UnicodeDecodeError) as exc:
        msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise ConfigError(f"planner params {str(file)!r} is not a readable TOML file: "
                          f"{msg}") from None


def make_planner(planner: str, file: str | Path | None = None, sets: list[str] = ()) -> Planner:
    """A ready :class:`Planner` running the named algorithm."""
    apf, algo = load_params(planner, file, sets)
    check_params(apf, algo)   # again where the values are used (load_params checked each)
    return Planner(PLANNERS[planner](algo), apf)
