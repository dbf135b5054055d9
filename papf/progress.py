"""A one-line live status of a run on stderr (rich), or a log line every 10 s sim time."""

from __future__ import annotations

import logging
import math
import sys

from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

log = logging.getLogger("papf.run")


class RunProgress:
    """``with RunProgress(...) as p: p.update(sim_s, dist_m, mAh, state)``."""

    def __init__(self, enabled: bool | None, timeout_s: float, world: str, planner: str):
        self.enabled = sys.stderr.isatty() if enabled is None else enabled
        self.timeout_s = timeout_s
        self._next_log_s = 10.0
        self._progress = Progress(
            TextColumn(f"[bold]{planner}[/] on {world}"), BarColumn(),
            TextColumn("{task.fields[status]}"), TimeElapsedColumn(),
            console=Console(stderr=True), transient=True,
        ) if self.enabled else None
        self._task = None

    def __enter__(self) -> RunProgress:
        if self._progress:
            self._progress.start()
            self._task = self._progress.add_task("run", total=self.timeout_s, status="starting")
        return self

    def update(self, sim_s: float, dist_m: float, charge_mAh: float, state: str) -> None:
        sim_s = max(sim_s, 0.0)
        text = (f"sim {sim_s:6.1f} s  to goal {dist_m:5.2f} m  {charge_mAh:6.2f} mAh  {state}"
                if not math.isnan(dist_m) else f"sim {sim_s:6.1f} s  {state}")
        if self._progress is not None:
            self._progress.update(self._task, completed=min(sim_s, self.timeout_s), status=text)
        elif sim_s >= self._next_log_s:
            self._next_log_s += 10.0
            log.info(text)

    def __exit__(self, *exc) -> None:
        if self._progress:
            self._progress.stop()
