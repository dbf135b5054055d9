"""Ports of the energy meter (see :mod:`common.ports`)."""

PORTS = (
    ("in", "odom", "Odometry"),                  # v, w
    ("in", "wheels", "WheelStates"),             # per-wheel speed and torque
    ("in?", "battery/measured", "BatteryVoltage"),   # the real robot's pack voltage
    ("out", "battery", "BatteryState"),          # V, I, P, mAh, J, SoC per paired stamp
)
VARIANTS: dict = {}
