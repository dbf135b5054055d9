"""The outcomes of a run and the exit code of each: one list for ``papf run`` (the launcher's
outcome judge), ``papf plan`` (offline) and ``papf goal`` (the bus tool)."""

from __future__ import annotations

OUTCOMES = ("reached", "stagnated", "collision", "timeout", "failed")
# exit codes of the commands that end with a run's outcome (2 is a usage error)
EXIT_CODES = {"reached": 0, "stagnated": 3, "collision": 4, "timeout": 5, "failed": 6}
