"""Sweeps: many independent runs on Dask distributed — a local cluster or an existing one.

:func:`map_runs` runs jobs one after the other, on a local Dask cluster of N workers, or on
an existing scheduler (docs/sweeps.md); results come back in job order, byte-identical to
a sequential sweep. Used by every experiment with many runs.
"""

from __future__ import annotations

import logging
import re
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TypeVar

from common.errors import ConfigError

J = TypeVar("J")
R = TypeVar("R")

# Local worker processes at most: each runs a stack (several processes) or an offline run; more
# than this is a typo (--workers 1000000 would fork until the machine stops), not a sweep.
MAX_WORKERS = 256

SCHEDULER_RE = re.compile(r"^(tcp|tls)://[\w.\-\[\]:]+:\d+$")


@dataclass(frozen=True)
class SweepOptions:
    workers: int = 1                  # local worker processes (1: sequential, no Dask)
    scheduler: str | None = None      # tcp://HOST:PORT of an existing Dask scheduler
    progress: bool | None = None      # None: a bar when stderr is a terminal, else a line per run

    def validate(self) -> None:
        """ConfigError naming the bad value (before anything starts)."""
        if not isinstance(self.workers, int) or not 1 <= self.workers <= MAX_WORKERS:
            raise ConfigError(f"--workers {self.workers!r}: need an integer in [1, {MAX_WORKERS}]")
        if self.scheduler is not None and not SCHEDULER_RE.match(self.scheduler):
            raise ConfigError(f"--scheduler {self.scheduler!r}: expected tcp://HOST:PORT "
                              "(a Dask scheduler, e.g. tcp://10.0.0.5:8786)")
        if self.scheduler is not None and self.workers != 1:
            raise ConfigError("--workers and --scheduler exclude each other: the cluster "
                              "behind --scheduler has its own workers")

    @property
    def distributed(self) -> bool:
        """Whether runs are spread over workers or a scheduler."""
        return self.workers > 1 or self.scheduler is not None


def run_namespace(index: int) -> str:
    """The key namespace of the sweep's ``index``-th run (the same however runs are spread)."""
    return f"sweep{index}"


def map_runs(fn: Callable[[J], R], jobs: Sequence[J], opts: SweepOptions,
             label: Callable[[J], str] = str, title: str = "sweep",
             line: Callable[[J, R], str] | None = None,
             on_done: Callable[[J, R], None] | None = None) -> list[R]:
    """``[fn(job) for job in jobs]`` (job order), on Dask when ``opts`` asks.

    ``fn`` and the jobs must pickle (a module-level function, dataclass jobs) when
    distributed; ``label(job)`` names a run on the progress bar; ``line(job, result)`` is
    the line printed per finished run (default: label, outcome, wall time);
    ``on_done(job, result)`` is called here the moment each run ends (to write it to disk:
    :mod:`papf.experiments.journal`).

    ``map_runs(fn, jobs, opts)`` returns ``[fn(job) for job in jobs]``, in job order, however
    the runs are spread:

    - ``workers = 1`` and no scheduler: one after the other in this process (no Dask at all);
    - ``workers = N``: a :class:`distributed.LocalCluster` of N single-threaded worker
      processes on this machine;
    - ``scheduler = "tcp://HOST:8786"``: the workers of an existing Dask cluster (other
      machines with papf-stack installed; docs/sweeps.md), results gathered here.

    Each run is isolated: a stack run gets its own router port (a free one on the machine
    that runs it) and its own key namespace (:func:`run_namespace`), so two runs on one
    machine never hear each other. A run is bit-for-bit reproducible for its seed, so the
    results — and the CSV written from them in job order — are byte-identical to a
    sequential sweep. One progress bar covers the whole sweep (a terminal), or one line per
    finished run (piped).

    Dask was chosen because it is pure Python (one ``pip install``), light on a 2-core
    laptop (a scheduler thread and N worker processes), and the same client code drives a
    ``LocalCluster`` and a remote ``tcp://`` scheduler; Ray or Celery need a server or a
    broker for the latter.
    """
    opts.validate()
    with SweepProgress(len(jobs), title, opts.progress, line) as progress:
        if not opts.distributed:
            out = []
            for job in jobs:
                t0 = time.monotonic()
                out.append(fn(job))
                if on_done is not None:
                    on_done(job, out[-1])
                progress.done(job, label(job), out[-1], time.monotonic() - t0)
            return out
        return _map_dask(fn, jobs, opts, label, progress, on_done)


def _map_dask(fn, jobs, opts: SweepOptions, label, progress: SweepProgress, on_done=None) -> list:
    from distributed import Client, LocalCluster, as_completed  # only when a sweep spreads

    # the scheduler of a LocalCluster runs here: its INFO lines would bury the progress bar
    logging.getLogger("distributed").setLevel(logging.WARNING)

    if opts.scheduler:
        cluster = None
        try:
            client = Client(opts.scheduler, timeout="20s")
        except OSError as exc:
            raise ConfigError(f"--scheduler {opts.scheduler}: no Dask scheduler answers "
                              f"({exc}); start one with `dask scheduler` (docs/sweeps.md)") from None
    else:  # single-threaded worker processes: a stack run already uses a core and more
        cluster = LocalCluster(n_workers=opts.workers, threads_per_worker=1, processes=True,
                               dashboard_address=None)
        client = Client(cluster)
    try:
        futures = client.map(_timed, [fn] * len(jobs), jobs, pure=False)
        index = {f.key: i for i, f in enumerate(futures)}
        results: list = [None] * len(jobs)
        for future in as_completed(futures):
            i = index[future.key]
            results[i], wall = future.result()   # a run's exception is raised here
            if on_done is not None:
                on_done(jobs[i], results[i])
            progress.done(jobs[i], label(jobs[i]), results[i], wall)
        return results
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def _timed(fn, job):
    t0 = time.monotonic()
    return fn(job), time.monotonic() - t0


class SweepProgress:
    """One bar over the whole sweep on a terminal; else one line per finished run (stderr)."""

    def __init__(self, total: int, title: str, enabled: bool | None = None, line=None):
        from rich.console import Console
        from rich.progress import (
            BarColumn,
            MofNCompleteColumn,
            Progress,
            TextColumn,
            TimeElapsedColumn,
        )

        console = Console(stderr=True)
        self.bar = console.is_terminal if enabled is None else enabled
        self.total, self.count, self.title, self.line = total, 0, title, line
        self._progress = Progress(TextColumn("{task.description}"), BarColumn(),
                                  MofNCompleteColumn(), TimeElapsedColumn(), console=console,
                                  disable=not self.bar)
        self._task = None

    def __enter__(self) -> SweepProgress:
        self._progress.__enter__()
        self._task = self._progress.add_task(self.title, total=self.total)
        return self

    def done(self, job, label: str, result, wall_s: float) -> None:
        """Count a finished job and show its line (above the progress bar when there is one)."""
        self.count += 1
        text = (self.line(job, result) if self.line else
                f"{label}: {getattr(result, 'outcome', 'done')} ({wall_s:.1f} s wall)")
        if self.bar:  # the line above the bar
            self._progress.update(self._task, advance=1, description=f"{self.title}: {label}")
            self._progress.console.print(text, highlight=False, markup=False, soft_wrap=True)
        else:
            print(f"[{self.count}/{self.total}] {text}", file=sys.stderr, flush=True)

    def __exit__(self, *exc) -> None:
        self._progress.__exit__(*exc)
