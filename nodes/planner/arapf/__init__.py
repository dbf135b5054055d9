"""AR-APF (adaptive repulsion, virtual walls)."""
