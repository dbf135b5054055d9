"""Progress of long work on stderr: a live line on a terminal, else one line per 10 %.

- :class:`DecileProgress` — any job with a fraction done (replay: messages; a goal: the
  share of the start distance covered). Piped (a file, CI, ``| tee``), it prints a line
  each time the job passes another 10 %, plus one every ``HEARTBEAT_S`` of wall time
  without one (so a stuck job still says it is alive).
- :class:`StepProgress` — a job of N steps (the runs of a study): a live bar on a
  terminal; piped, one line per finished step (``wang: 3/16  fig 6 wang-apf reached``).
- :class:`RunProgress` — a run of the stack: the share of the straight-line distance
  from the start to the goal covered (the closest the robot has been), sim time, charge
  and the planner's state.
"""

from __future__ import annotations

import math
import sys
import threading
import time
from collections.abc import Callable

from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

HEARTBEAT_S = 30.0   # [s wall] longest silence of the piped mode


def _err(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


class DecileProgress:
    """``with DecileProgress("replay") as p: p.fraction(done / total, "detail")``.

    ``enabled``: None = a live bar when stderr is a terminal, else decile lines;
    True = the live bar; False = nothing. ``out`` receives the piped lines.
    """

    def __init__(self, label: str, enabled: bool | None = None,
                 out: Callable[[str], None] | None = None, clock: Callable[[], float] = time.monotonic):
        self.label, self.out, self.clock = label, out or _err, clock
        self.live = sys.stderr.isatty() if enabled is None else enabled
        self.quiet = enabled is False
        self._decile = -1
        self._start_distance: float | None = None
        self._best = 0.0
        self._last_line = clock()
        self._bar = Progress(TextColumn(f"[bold]{escape(label)}[/]"), BarColumn(),
                             TextColumn("{task.percentage:>3.0f} %  {task.fields[text]}",
                                        markup=False),
                             TimeElapsedColumn(), console=Console(stderr=True),
                             transient=True) if self.live and not self.quiet else None
        self._task = None

    def __enter__(self) -> DecileProgress:
        if self._bar is not None:
            self._bar.start()
            self._task = self._bar.add_task(self.label, total=1.0, text="")
        return self

    def __exit__(self, *exc) -> None:
        if self._bar is not None:
            self._bar.stop()

    def fraction(self, done: float, text: str = "") -> None:
        """Report ``done`` in [0, 1] (it may go down; lines follow the best so far)."""
        if self.quiet:
            return
        done = min(max(done, 0.0), 1.0) if math.isfinite(done) else 0.0
        self._best = max(self._best, done)
        if self._bar is not None:
            self._bar.update(self._task, completed=done, text=text)
            return
        decile = int(self._best * 10 + 1e-9)
        now = self.clock()
        if decile > self._decile or now - self._last_line >= HEARTBEAT_S:
            self._decile = max(decile, self._decile)
            self._last_line = now
            self.out(f"{self.label}: {100 * self._best:3.0f} %" + (f"  {text}" if text else ""))

    def distance(self, remaining_m: float, text: str = "") -> None:
        """Report the remaining distance [m]: done = 1 - remaining / the first one reported."""
        if math.isnan(remaining_m):
            return
        if self._start_distance is None:
            self._start_distance = max(remaining_m, 1e-9)
        self.fraction(1.0 - remaining_m / self._start_distance, text)


class StepProgress:
    """``with StepProgress("wang", total=16) as p: p.step("fig 5 reached")`` (see module doc).

    ``enabled``: None = the live bar when stderr is a terminal, else one line per step;
    True = the live bar; False = nothing. ``out`` receives the piped lines. ``after_s``: show
    nothing for a job done within that many seconds; past them, the bar (or a line saying
    what is under way, :meth:`doing`) appears and every step shows as usual.
    """

    def __init__(self, label: str, total: int, enabled: bool | None = None,
                 out: Callable[[str], None] | None = None, after_s: float = 0.0):
        self.label, self.total, self.done, self.out = label, max(int(total), 1), 0, out or _err
        live = sys.stderr.isatty() if enabled is None else enabled
        self.quiet = enabled is False
        self._bar = Progress(TextColumn(f"[bold]{escape(label)}[/]"), BarColumn(),
                             TextColumn("{task.completed}/{task.total}  {task.fields[text]}",
                                        markup=False),
                             TimeElapsedColumn(), console=Console(stderr=True),
                             transient=True) if live and not self.quiet else None
        self._task = None
        self._now = ""                       # the step under way (doing)
        self._lock = threading.Lock()
        self._shown = after_s <= 0
        self._timer = None if self._shown or self.quiet else threading.Timer(after_s, self._show)
        if self._timer is not None:
            self._timer.daemon = True

    def __enter__(self) -> StepProgress:
        if self._timer is not None:
            self._timer.start()
        elif self._shown:
            self._start_bar()
        return self

    def __exit__(self, *exc) -> None:
        with self._lock:
            if self._timer is not None:
                self._timer.cancel()
            self._shown = False               # nothing more once the job is over
            if self._bar is not None and self._task is not None:
                self._bar.stop()

    def _start_bar(self) -> None:
        if self._bar is not None:
            self._bar.start()
            self._task = self._bar.add_task(self.label, total=self.total, completed=self.done,
                                            text=self._now)

    def _show(self) -> None:
        """``after_s`` passed and the job is still going: show it from now on."""
        with self._lock:
            if self._shown or self.quiet:
                return
            self._shown = True
            if self._bar is not None:
                self._start_bar()
            else:
                self.out(f"{self.label}: {self.done}/{self.total}"
                         + (f"  {self._now} ..." if self._now else ""))

    def doing(self, text: str) -> None:
        """What the next step is (``reading run.mcap``): shown with the bar, or in the line
        printed when ``after_s`` passes during it."""
        with self._lock:
            self._now = text
            if self._shown and self._bar is not None and self._task is not None:
                self._bar.update(self._task, text=text)

    def step(self, text: str = "") -> None:
        """One more step done; ``text`` says what it was (a run's outcome)."""
        with self._lock:
            self.done += 1
            if self.quiet or not self._shown:
                return
            if self._bar is not None:
                self._bar.update(self._task, completed=self.done, total=self.total, text=text)
                return
            self.out(f"{self.label}: {self.done}/{self.total}" + (f"  {text}" if text else ""))


class RunProgress:
    """``with RunProgress(...) as p: p.update(sim_s, dist_m, mAh, state)`` (see module doc)."""

    def __init__(self, enabled: bool | None, timeout_s: float, world: str, planner: str,
                 out: Callable[[str], None] | None = None):
        self.timeout_s = timeout_s
        self._p = DecileProgress(f"{planner} on {world}", enabled, out)

    def __enter__(self) -> RunProgress:
        self._p.__enter__()
        return self

    def update(self, sim_s: float, dist_m: float, charge_mAh: float, state: str) -> None:
        """Show sim time [s], distance to goal [m], charge [mAh] and the state."""
        sim_s = max(sim_s, 0.0)
        text = (f"sim {sim_s:6.1f} s  to goal {dist_m:5.2f} m  {charge_mAh:6.2f} mAh  {state}"
                if not math.isnan(dist_m) else f"sim {sim_s:6.1f} s  {state}")
        if math.isnan(dist_m):
            self._p.fraction(0.0, text)
        else:
            self._p.distance(dist_m, text)

    def __exit__(self, *exc) -> None:
        self._p.__exit__(*exc)
