"""Confidence intervals of the crowd experiment's figures over seeds.

A figure measured once per run (time, separation, time in a zone, ...) is summarised by its
mean over the runs and the half-width of a 95 % Student t-interval, ``t(0.975, n - 1) s /
sqrt(n)`` (s the sample standard deviation): the runs are independent seeds, and the
t-interval is exact for normal data and close for the small samples a seed sweep gives (a
bootstrap of 10 values says little about its own tails). A rate (success, collision) is a
binomial proportion: its 95 % interval is Wilson's score interval (Wilson 1927), which stays
inside [0, 100] % and is not empty at 0 % or 100 %, where the normal approximation fails.
"""

from __future__ import annotations

import math
from collections.abc import Iterable

Z95 = 1.959963984540054        # [-] the standard normal's 97.5 % quantile


def t_interval(values: Iterable) -> tuple[float | str, float | str]:
    """(mean, 95 % half-width) of the numbers among ``values`` ('' entries skipped); ('', '')
    without any, (mean, '') with one."""
    from scipy.stats import t

    vals = [float(v) for v in values if v != "" and v is not None and math.isfinite(float(v))]
    if not vals:
        return "", ""
    n = len(vals)
    mean = sum(vals) / n
    if n < 2:
        return round(mean, 3), ""
    sd = math.sqrt(sum((v - mean) ** 2 for v in vals) / (n - 1))
    return round(mean, 3), round(float(t.ppf(0.975, n - 1)) * sd / math.sqrt(n), 3)


def wilson(successes: int, n: int) -> tuple[float, float]:
    """95 % Wilson score interval [%] of ``successes`` out of ``n``."""
    if n <= 0:
        return 0.0, 100.0
    p = successes / n
    centre = (p + Z95 ** 2 / (2 * n)) / (1 + Z95 ** 2 / n)
    half = Z95 * math.sqrt(p * (1 - p) / n + Z95 ** 2 / (4 * n * n)) / (1 + Z95 ** 2 / n)
    return round(100 * max(centre - half, 0.0), 1), round(100 * min(centre + half, 1.0), 1)
