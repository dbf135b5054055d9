"""The one stagnation rule (nodes/planner/stagnation.py): the planner core's and the offline
3-D point robot's; a gap without scans (a link outage) is not time without progress."""

import numpy as np

from common.units import NS_PER_S
from nodes.planner.field import APFParams
from nodes.planner.stagnation import INPUT_GAP_NS, StagnationWatch

APF = APFParams(stagnation_window_s=2.0, stagnation_progress_m=0.1, stagnation_roam_m=0.5,
                stagnation_max_s=5.0)


S = 1_000_000_000   # [ns]


def _run(points, dist=3.0, dt_s=0.5, searching=False) -> tuple[int, str]:
    """Feed positions every ``dt_s`` at a constant distance; (index, reason) of the verdict."""
    w = StagnationWatch()
    for k, pos in enumerate(points):
        why = w.check(round(k * dt_s * NS_PER_S), dist, APF, np.asarray(pos, float), searching)
        if why:
            return k, why
    return -1, ""


def test_no_progress_within_the_window_stagnates_in_3d():
    k, why = _run([(0.0, 0.0, 0.0)] * 10)
    assert k == 5 and "in 2.0 s" in why        # 2.5 s > window 2 s


def test_roaming_in_3d_restarts_the_window_until_the_max_time():
    """Moving 0.6 m (> roam 0.5 m) along z each second keeps the window open; stagnation_max_s
    still ends the run (the rule the old offline 3-D watch lacked)."""
    k, why = _run([(0.0, 0.0, 0.6 * (i // 2)) for i in range(20)])
    assert k == 11 and "in 5.0 s" in why       # 5.5 s > max 5 s, window never 2 s old


def test_searching_restarts_the_window():
    k, why = _run([(0.0, 0.0)] * 20, searching=True)
    assert "in 5.0 s" in why


def test_progress_resets_both_clocks_and_a_new_goal_resets_the_watch():
    w = StagnationWatch()
    for k in range(20):   # 0.2 m closer every 0.5 s: never stagnated
        assert w.check(round(k * 0.5 * NS_PER_S), 10.0 - 0.2 * k, APF, np.zeros(2)) == ""
    w.reset()
    assert w.best == float("inf") and w.anchor is None


def _watch_over(times_s, dist=lambda t: 5.0):
    apf, watch = APFParams(), StagnationWatch()
    return [watch.check(int(t * S), dist(t), apf, (0.0, 0.0)) for t in times_s]


def test_a_gap_without_scans_is_not_time_without_progress():
    window = APFParams().stagnation_window_s
    steered = [k * 0.1 for k in range(int(5 / 0.1))]              # 5 s of scans, standing
    after = [25.0 + k * 0.1 for k in range(10)]                   # then 20 s of nothing
    assert not any(_watch_over(steered + after))                  # judged on 6 s steered
    assert window < 25.0


def test_without_a_gap_the_same_standstill_stagnates():
    times = [k * 0.1 for k in range(int(26 / 0.1))]
    assert any(_watch_over(times))


def test_short_gaps_count_as_ever():
    gap = INPUT_GAP_NS / S - 0.2                                  # below the gap: still counted
    times, t = [], 0.0
    while t < 26:
        times.append(t)
        t += gap
    assert any(_watch_over(times))
