"""The energy report of recorded runs (docs/recording.md; docs/experiments-energy.md).

- :func:`~papf.report.metrics.run_metrics` — one run's figures from its MCAP file alone;
- :class:`~papf.report.remeter.Remeter` / :func:`~papf.report.remeter.remeter_file` —
  re-meter recorded odometry and wheel states with either energy model;
- :mod:`~papf.report.tables` — per-planner mean ± sd, PAPF vs APF next to the paper;
- :mod:`~papf.report.figures` — trajectories, charge bars, Fig. 13-style motion plots;
- :func:`~papf.report.report.build_report` — all of it into report.md, report.csv, PNGs.
"""

from papf.report.metrics import RunMetrics, Series, run_metrics
from papf.report.remeter import Remeter, battery_at, remeter_file
from papf.report.report import Report, build_report, find_recordings

__all__ = ["Remeter", "Report", "RunMetrics", "Series", "battery_at", "build_report",
           "find_recordings", "remeter_file", "run_metrics"]
