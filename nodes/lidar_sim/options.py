"""Declared ranges of the LiDAR node's options (:mod:`common.params`), without pybullet.

Checked when the command line is parsed (``python -m nodes.lidar_sim``) and again by
:class:`nodes.lidar_sim.core.LidarParams`. ``MAX_BEAMS`` stays below pybullet's ray
batch size (16384), so one scan is one ``rayTestBatch`` call.
"""

from __future__ import annotations

from common.params import SEED, Spec, integer, num, pos

MAX_BEAMS = 16_000      # [-] rays per revolution (RPLIDAR A3: 16 k samples/s)

OPTIONS: dict[str, Spec] = {
    "beams": integer(1, MAX_BEAMS), "scan_hz": pos(100.0, "Hz"),
    "noise_sd": num(0.0, 1.0, "m"), "noise_rel": num(0.0, 1.0), "seed": SEED,
}
