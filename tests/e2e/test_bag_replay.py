"""papf replay of a rosbag2 from the robot feeds our nodes: a fresh energy-meter process
re-meters the bag's drive to what ``papf report`` re-meters from the file."""


import pytest

from papf.recording.replay import replay
from papf.report.remeter import remeter_file
from tests.support.bags import write_bag
from tests.support.e2e import metered_bus

pytestmark = pytest.mark.e2e


def test_replayed_bag_is_re_metered_by_the_energy_meter_node(tmp_path, spawn):
    bag = tmp_path / "lab-run"
    truth = write_bag(bag)
    expected = remeter_file(bag, "motor")[-1]      # the report's re-meter, from the file
    ns = "replayed"
    with metered_bus(spawn, ns) as (s, got):
        stats = replay(bag, s, rate=4.0, namespace=ns,
                       keys=["rosbot/odom", "rosbot/wheels", "rosbot/battery/measured"])
        assert stats.per_key[f"{ns}/odom"] == 1201
        got.wait_for(expected.stamp_ns)
    last = max(got.items, key=lambda b: b.stamp_ns)
    assert last.stamp_ns == expected.stamp_ns == int(truth.span_s * 1e9)
    assert last.charge_used_mAh == pytest.approx(expected.charge_used_mAh, rel=1e-3)
