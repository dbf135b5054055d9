"""Declared type and valid range of a node setting, and the one check of a value against it.

Every setting of every node has a :class:`Spec`; :func:`check_value` is the only place a
value is accepted (``--set``, ``--params``, options, live parameters). Safety settings'
ranges exclude every value that switches the protection off.
"""

from __future__ import annotations

import argparse
import dataclasses
import difflib
import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

from common.errors import ConfigError

_TRUE = ("true", "1", "yes", "on")
_FALSE = ("false", "0", "no", "off")


@dataclass(frozen=True)
class Spec:
    """A setting's type (``float``, ``int``, ``bool`` or ``str``) and valid values."""

    kind: type
    lo: float | None = None          # lower bound (None: unbounded)
    hi: float | None = None          # upper bound (None: unbounded)
    lo_open: bool = False            # True: lo itself is not valid
    hi_open: bool = False
    choices: tuple[str, ...] = ()    # str settings: the valid values
    unit: str = ""
    safety: bool = False             # the range keeps a protection switched on (check_value)

    def describe(self) -> str:
        """The valid values in words, e.g. ``a number in (0, 5] m``."""
        if self.kind is bool:
            return "true or false"
        if self.kind is str:
            return "one of " + ", ".join(self.choices)
        what = "an integer" if self.kind is int else "a finite number"
        if self.lo is None and self.hi is None:
            return what
        fmt = (lambda v: str(int(v))) if self.kind is int else (lambda v: f"{v:g}")
        lo = "-inf" if self.lo is None else fmt(self.lo)
        hi = "inf" if self.hi is None else fmt(self.hi)
        left = "(" if self.lo_open or self.lo is None else "["
        right = ")" if self.hi_open or self.hi is None else "]"
        return f"{what} in {left}{lo}, {hi}{right}" + (f" {self.unit}" if self.unit else "")

    def contains(self, value: float) -> bool:
        """Whether ``value`` lies in the range (open ends excluded)."""
        if self.lo is not None and (value < self.lo or (self.lo_open and value == self.lo)):
            return False
        return not (self.hi is not None and (value > self.hi or (self.hi_open and value == self.hi)))


def num(lo: float | None, hi: float | None, unit: str = "", *, lo_open: bool = False,
        hi_open: bool = False, safety: bool = False) -> Spec:
    """A finite float in the given range."""
    return Spec(float, lo, hi, lo_open, hi_open, unit=unit, safety=safety)


def pos(hi: float, unit: str = "", *, safety: bool = False) -> Spec:
    """A float in ``(0, hi]``."""
    return Spec(float, 0.0, hi, lo_open=True, unit=unit, safety=safety)


def integer(lo: int | None, hi: int | None, unit: str = "") -> Spec:
    """A Spec of an integer in [lo, hi] (None: unbounded) in ``unit``."""
    return Spec(int, lo, hi, unit=unit)


FLAG = Spec(bool)
SEED = Spec(int, 0, 2**32 - 1)   # every noise seed (numpy's SeedSequence takes any, pybullet not)
TIMEOUT = Spec(float, 0.0, 1e6, lo_open=True, unit="s")   # a run's limit: 11.6 days, not forever
PORT = Spec(int, 1, 65535)       # a TCP port
RATE_HZ = Spec(float, 0.0, 1000.0, lo_open=True, unit="Hz")   # a tool's publishing rate


def choice(*values: str) -> Spec:
    """A Spec of a string, one of ``values``."""
    return Spec(str, choices=tuple(values))


def check_value(name: str, value: Any, spec: Spec) -> Any:
    """``value`` as ``spec.kind``, in range; ConfigError ``name=value: must be ...`` otherwise.

    ``value`` may be text (``--set``, command line) or already typed (TOML, a live
    parameter). An int is accepted for a float setting; a bool never counts as a number.

    Every setting of every node (planner parameters, energy-meter constants, driver, LiDAR
    and planner-node options) has a :class:`Spec`. :func:`check_value` is the only place a
    value is accepted: ``--set name=value``, a ``--params`` TOML file, command-line options
    (:func:`arg_type`) and any live-parameter path (e.g. a viewer's parameter panel) call it,
    and the node that uses the setting checks its whole parameter set again with
    :func:`check_all` before acting on it.

    Safety settings (``safety=True``, e.g. the repulsion range ``d_o`` or the command
    watchdog) have ranges that exclude every value that would switch the protection off:
    zero, negative, ``nan`` and ``inf`` are refused.
    """
    typed = _typed(value, spec.kind)
    ok = typed is not None
    if ok and spec.kind in (int, float):
        ok = math.isfinite(typed) and spec.contains(typed)
    elif ok and spec.kind is str and spec.choices:
        ok = typed in spec.choices
    if not ok:
        raise ConfigError(f"{name}={_show(value)}: must be {spec.describe()}")
    return typed


def _typed(value: Any, kind: type) -> Any:
    """``value`` converted to ``kind``, or None when it is not one."""
    if isinstance(value, str):
        text = value.strip()
        if kind is bool:
            low = text.lower()
            return True if low in _TRUE else False if low in _FALSE else None
        if kind is str:
            return text
        try:
            return kind(text)
        except (ValueError, OverflowError):
            return None
    if isinstance(value, bool):
        return value if kind is bool else None
    if kind is float and isinstance(value, (int, float)):
        try:
            return float(value)
        except OverflowError:
            return None
    return value if isinstance(value, kind) else None


def _show(value: Any) -> str:
    text = value if isinstance(value, str) and value.isprintable() else repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def check_all(obj: Any, specs: Mapping[str, Spec], where: str = "") -> None:
    """Check every field of a params dataclass ``obj`` (what a node does before using it)."""
    for f in dataclasses.fields(obj):
        if f.name not in specs:
            raise ConfigError(f"{where or type(obj).__name__}: setting {f.name!r} has no declared range")
        check_value(f.name, getattr(obj, f.name), specs[f.name])


def unknown_name(name: str, valid: Iterable[str], what: str = "setting") -> ConfigError:
    """ConfigError for an unknown name, with a "did you mean" when one is close."""
    valid = sorted(valid)
    close = difflib.get_close_matches(name, valid, n=1, cutoff=0.6)
    hint = f"; did you mean {close[0]!r}?" if close else ""
    return ConfigError(f"unknown {what} {name!r}{hint} (valid: {', '.join(valid)})")


def arg_type(name: str, spec: Spec):
    """An argparse ``type=`` that checks the option against ``spec`` (exit 2, one line)."""
    def parse(text: str):
        try:
            return check_value(name, text, spec)
        except ConfigError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None
    parse.__name__ = spec.kind.__name__
    return parse
