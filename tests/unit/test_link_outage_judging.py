"""A link outage is judged as the link's, not the planner's: the planner's stagnation watch
does not count time it got no scan, and a run that ended after an outage the laptop heard
names the link in its reason (even when the robot's last report predates the outage)."""

from __future__ import annotations

from nodes.planner.field import APFParams
from nodes.planner.stagnation import INPUT_GAP_NS, StagnationWatch
from papf.launch.linkwatch import LinkWatch

S = 1_000_000_000   # [ns]


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


def test_a_run_ended_after_an_outage_the_laptop_heard_names_the_link():
    watch = LinkWatch()
    watch.heard(0)
    watch.heard(20 * S)
    watch.tick(21 * S + 100)                                      # silent since 20 s: lost
    watch.heard(41 * S)                                           # back after 21 s
    reason = watch.blame("stagnated", "no progress", 42 * S, 42.0)
    assert reason is not None and reason.startswith("the link: nothing from the robot for 21.0 s")
    assert "(what the run saw: no progress)" in reason


def test_a_short_blip_is_not_blamed():
    watch = LinkWatch()
    watch.heard(0)
    watch.tick(2 * S)                                             # 2 s lost of a 100 s run
    watch.heard(2 * S + 100)
    assert watch.blame("stagnated", "no progress", 100 * S, 100.0) is None
