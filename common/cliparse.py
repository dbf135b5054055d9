"""The one command-line parser of every ``papf`` command and every ``python -m nodes.<node>``.

:class:`ArgumentParser` is :class:`argparse.ArgumentParser` with the usage errors a user
can act on:

- a misspelt option is named with the nearest ones the parser knows (``papf run --wrld
  energy``: ``unrecognized option --wrld; did you mean --world?``), found *before*
  argparse's own checks, so a misspelt required option is not reported as a missing one;
- a misspelt choice or subcommand gets the same (``papf rnu``: ``did you mean run?``);
- the error is one line (``prog: what was wrong ... (see prog --help)``), whole, wrapped
  for the terminal when stderr is one (:func:`common.text.error_text`), and exit 2.

The suggestions come from the parser's own option strings and choices (difflib), so every
option any command or node declares has them without a list kept elsewhere. Subparsers
made by :meth:`add_subparsers` are of the same class (argparse's default).
"""

from __future__ import annotations

import argparse
import re
import sys
from collections.abc import Sequence

from common.text import error_text, safe_text, suggest

_NEGATIVE = re.compile(r"^-\d+$|^-\d*\.\d+([eE][-+]?\d+)?$")   # argparse's negative-number look


class ArgumentParser(argparse.ArgumentParser):
    """argparse with did-you-mean for options, choices and subcommands, and one-line errors."""

    def parse_known_args(self, args: Sequence[str] | None = None, namespace=None):
        arg_list = list(sys.argv[1:] if args is None else args)
        unknown = self._first_unknown_option(arg_list)
        if unknown is not None:
            name = unknown.split("=", 1)[0]
            self.error(f"unrecognized option {safe_text(name)}"
                       f"{suggest(name, self._long_options()) or self._valid_hint()}")
        return super().parse_known_args(arg_list, namespace)

    def _check_value(self, action, value) -> None:
        try:
            super()._check_value(action, value)
        except argparse.ArgumentError:
            if action.choices is None or isinstance(action.choices, range):
                raise
            choices = [str(c) for c in action.choices]
            hint = suggest(value, choices) or f"; valid: {', '.join(choices)}"
            raise argparse.ArgumentError(action, f"invalid choice {safe_text(value)!s}{hint}") from None

    def error(self, message: str):
        """One line (wrapped for a terminal), the way to the help, exit 2."""
        self.exit(2, error_text(self.prog, f"{message} (see {self.prog} --help)", sys.stderr) + "\n")

    def _long_options(self) -> list[str]:
        return sorted({s for a in self._actions for s in a.option_strings
                       if s.startswith("--") and a.help != argparse.SUPPRESS})

    def _valid_hint(self) -> str:
        return f"; valid options: {', '.join(self._long_options())}" if self._long_options() else ""

    def _first_unknown_option(self, arg_list: list[str]) -> str | None:
        """The first token that is written as an option but is none of this parser's (nor an
        abbreviation argparse would take). Tokens after ``--``, and after the first positional
        of a parser whose remaining tokens belong to a subcommand or pass through (REMAINDER),
        are not this parser's to judge."""
        hands_on = any(isinstance(a, argparse._SubParsersAction) or a.nargs == argparse.REMAINDER
                       for a in self._actions if not a.option_strings)
        takes_value = False
        for token in arg_list:
            if token == "--":
                return None
            if not token.startswith("-") or token == "-" or (_NEGATIVE.match(token)
                                                             and not self._has_negative_number_optionals):
                if hands_on and not takes_value:
                    return None   # the subcommand (or the pass-through) starts here
                takes_value = False
                continue
            action = self._known(token)
            if action is None:   # right after an option that wants a value: argparse says
                return None if takes_value else token   # "expected one argument" better
            takes_value = action.nargs != 0 and "=" not in token and not (
                len(token) > 2 and not token.startswith("--"))   # -n5: the value is attached
        return None

    def _known(self, token: str):
        """The action of an option token (exact, ``--opt=value``, an abbreviation argparse
        accepts, or a short option with its value attached), else None."""
        actions = self._option_string_actions
        name = token.split("=", 1)[0] if token.startswith("--") else token
        if name in actions:
            return actions[name]
        if not token.startswith("--"):
            return actions.get(token[:2])   # -n5, -vq: argparse's own reading of short options
        if self.allow_abbrev:
            starts = {actions[s] for s in actions if s.startswith(name)}
            if len(starts) == 1:
                return starts.pop()
        return None
