"""papf bench rx: a subscriber takes every burst with either handler (real Zenoh sessions)."""

from __future__ import annotations

import threading

import pytest

from bench import bench_rx
from papf.launch.supervisor import free_port, wait_port
from tests.support.cli import papf

pytestmark = pytest.mark.bus


@pytest.mark.parametrize("handler", bench_rx.HANDLERS)
def test_the_subscriber_takes_the_bursts_and_counts_its_threads_cpu(handler):
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    pub = threading.Thread(target=bench_rx.publish, args=(endpoint, 4, 100, 0.01, 1.6))
    pub.start()
    assert wait_port(int(endpoint.rsplit(":", 1)[1]), 10.0)   # the publisher listens
    try:
        row = bench_rx.subscribe(endpoint, 4, handler, "idle", 1.0)
    finally:
        pub.join()
    # 4 samples per 10 ms burst for 1 s: far more than 40 once the sessions met
    assert row["handler"] == handler and row["main_thread"] == "idle"
    assert row["samples"] > 40 and row["rx_us_per_sample"] >= 0 and row["main_cpu_s"] >= 0


def test_a_bad_figure_is_one_line_before_any_process():
    res = papf("bench", "rx", "--seconds", "nan")
    assert res.returncode == 2 and "--seconds nan: must be a number > 0" in res.stderr
    assert "Traceback" not in res.stderr
