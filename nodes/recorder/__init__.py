"""recorder node."""
