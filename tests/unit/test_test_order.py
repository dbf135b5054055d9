"""The order the parallel workers take the tests in (tests/support/order.py)."""

from hypothesis import given
from hypothesis import strategies as st

from tests.support.order import block_sizes, longest_first, read_durations


def test_block_sizes_are_worksteal_first_shares():
    assert block_sizes(10, 4) == [2, 2, 3, 3]
    assert block_sizes(3, 4) == [0, 1, 1, 1]
    assert sum(block_sizes(1989, 4)) == 1989


def test_the_long_tests_are_spread_each_block_longest_first():
    seconds = {"a": 40, "b": 30, "c": 20, "d": 10, "e": 1, "f": 1, "g": 1, "h": 1}
    order = longest_first(list("hgfedcba"), seconds, 2)
    first, second = order[:4], order[4:]
    assert {"a", "b"} & set(first) and {"a", "b"} & set(second)   # not both in one block
    for block in (first, second):
        assert [seconds[n] for n in block] == sorted((seconds[n] for n in block), reverse=True)


def test_no_durations_or_one_worker_keep_the_collection_order():
    ids = ["x", "y", "z"]
    assert longest_first(ids, {}, 4) == ids
    assert longest_first(ids, {"x": 1.0}, 1) == ids


def test_an_unmeasured_test_counts_as_the_median():
    order = longest_first(["new", "slow", "fast", "mid"], {"slow": 9, "mid": 5, "fast": 1}, 2)
    assert sorted(order) == ["fast", "mid", "new", "slow"]
    assert order.index("slow") in (0, 2)   # the head of a block


@given(st.dictionaries(st.text(min_size=1, max_size=5), st.floats(0, 100), min_size=1),
       st.integers(1, 6))
def test_every_test_once(seconds, workers):
    ids = sorted(seconds)
    assert sorted(longest_first(ids, seconds, workers)) == ids


def test_the_committed_durations_name_tests_and_seconds():
    seconds = read_durations()
    assert seconds, "tests/durations.csv: written by papf bench suite --tests-csv"
    assert all("::" in n and s >= 0 for n, s in seconds.items())
