"""The order the parallel workers take the tests in: the longest first, spread over the workers.

pytest-xdist's ``worksteal`` gives each of W workers a contiguous block of the collected tests
(the first ``N // W``, then a ``// (W - 1)`` share of the rest, …) and lets an idle worker
take the second half of the longest queue. In the files' own order the long end-to-end cases
sit together: one worker got most of them, and the run ended on a tail of one long test while
the other core idled. :func:`longest_first` lays the collection out so that each block holds
a fair share of the measured time with its own longest tests first (what is stolen, the end
of a queue, is then its shortest); the seconds come from ``tests/durations.csv``, written by
``papf bench suite --tests-csv`` (a test not in it counts as the median). It changes which
worker runs a test and when, never what a test does.
"""

from __future__ import annotations

import csv
import statistics
from collections.abc import Sequence
from pathlib import Path

DURATIONS = Path(__file__).resolve().parents[1] / "durations.csv"


def read_durations(path: Path = DURATIONS) -> dict[str, float]:
    """``{nodeid: wall seconds}`` from ``path``; empty where there is no such file."""
    try:
        with path.open(newline="") as fh:
            return {row["nodeid"]: float(row["wall_s"]) for row in csv.DictReader(fh)}
    except (OSError, KeyError, ValueError):
        return {}


def block_sizes(n: int, workers: int) -> list[int]:
    """The sizes of worksteal's first blocks: each idle worker in turn takes
    ``len(pending) // workers_left``."""
    sizes = []
    for i in range(workers):
        sizes.append(n // (workers - i))
        n -= sizes[-1]
    return sizes


def longest_first(nodeids: Sequence[str], seconds: dict[str, float], workers: int) -> list[str]:
    """``nodeids`` reordered for ``workers`` worksteal workers: the longest test to the block
    with the least time so far that has room, then each block longest first."""
    if workers < 2 or not seconds:
        return list(nodeids)
    default = statistics.median(seconds.values())
    cost = {n: seconds.get(n, default) for n in nodeids}
    sizes = block_sizes(len(nodeids), workers)
    blocks: list[list[str]] = [[] for _ in sizes]
    totals = [0.0] * len(sizes)
    for nodeid in sorted(nodeids, key=lambda n: (-cost[n], n)):
        k = min((i for i in range(len(sizes)) if len(blocks[i]) < sizes[i]),
                key=lambda i: (totals[i], i))
        blocks[k].append(nodeid)
        totals[k] += cost[nodeid]
    return [n for block in blocks for n in block]
