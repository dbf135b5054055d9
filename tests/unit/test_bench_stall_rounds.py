"""bench/stall_rounds.py reads a round's pytest output: tests, stalls, the planner's missing partner."""

from bench.stall_rounds import parse

HELD = ("E   Failed: again: ['base_driver at 19.60 s: no cmd_vel with stamp_ns=19600000000 within "
        "30 s (wall); free running in real time until a command answers the latest scan', \"launcher: "
        "the nodes' last stamps: base_driver (5 peer links) took cmd_vel 19.50, events 19.60; put "
        "odom 19.60 | planner (5 peer links) took goal 0.00, objects 19.50, odom 19.60, scan 19.60; "
        "put cmd_vel 19.50 | tracker (5 peer links) took odom 19.60, scan 19.60; put objects 19.60\"]")


def test_a_stalled_round_names_the_held_stamp_and_the_partner_the_planner_missed():
    text = f"{HELD}\nE   [base_driver] lockstep: no cmd_vel with stamp_ns=19600000000 within 30 s\n" \
           "1 failed, 2 passed in 113.58s"
    assert parse(text) == {"passed": 2, "failed": 1, "stalls": 1, "held_at_s": "19.60",
                           "missing": "objects"}


def test_a_clean_round_has_no_stall():
    assert parse("3 passed in 78.2s") == {"passed": 3, "failed": 0, "stalls": 0, "held_at_s": "",
                                         "missing": ""}
