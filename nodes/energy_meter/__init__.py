"""energy_meter node: emulates the PAPF paper's charge measurement (docs/energy.md, docs/energy.md).

``core.EnergyMeter`` (pairing + integration), ``models`` (paper eq. (6), DC motors),
``battery`` (3S Li-ion pack); ``python -m nodes.energy_meter`` runs it as a process.
"""
