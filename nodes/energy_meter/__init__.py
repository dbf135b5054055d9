"""energy_meter node."""
