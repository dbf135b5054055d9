"""papf replay of a rosbag2 from the robot feeds our nodes: a fresh energy-meter process
re-meters the bag's drive to what ``papf report`` re-meters from the file."""

import sys
import threading
import time

import pytest
import zenoh

from common.transport import wait_alive, zenoh_config
from papf.launch.supervisor import free_port, wait_port
from papf.recording.replay import replay
from papf.report.remeter import remeter_file
from schemas import BatteryState, Keys
from tests.support.bags import write_bag

pytestmark = pytest.mark.e2e


def test_replayed_bag_is_re_metered_by_the_energy_meter_node(tmp_path, spawn):
    bag = tmp_path / "lab-run"
    truth = write_bag(bag)
    expected = remeter_file(bag, "motor")[-1]      # the report's re-meter, from the file
    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    spawn("router", [sys.executable, "-m", "papf.launch.router", "--listen", endpoint])
    assert wait_port(port, 15)
    ns = "replayed"
    with zenoh.open(zenoh_config("client", [endpoint])) as s:
        spawn("energy_meter", [sys.executable, "-m", "nodes.energy_meter", "--connect", endpoint,
                               "--namespace", ns, "--model", "motor"])
        assert not wait_alive(s, Keys(ns), ["energy_meter"], timeout_s=30)
        got, lock = [], threading.Lock()

        def on_battery(sample):
            with lock:
                got.append(BatteryState.from_bytes(sample.payload.to_bytes()))

        sub = s.declare_subscriber(Keys(ns).battery, on_battery)
        stats = replay(bag, s, rate=4.0, namespace=ns,
                       keys=["rosbot/odom", "rosbot/wheels", "rosbot/battery/measured"])
        assert stats.per_key[f"{ns}/odom"] == 1201
        deadline = time.monotonic() + 30     # the meter's last states may still be coming
        while time.monotonic() < deadline:
            with lock:
                if got and got[-1].stamp_ns >= expected.stamp_ns:
                    break
            time.sleep(0.05)
        sub.undeclare()
    last = max(got, key=lambda b: b.stamp_ns)
    assert last.stamp_ns == expected.stamp_ns == int(truth.span_s * 1e9)
    assert last.charge_used_mAh == pytest.approx(expected.charge_used_mAh, rel=1e-3)
