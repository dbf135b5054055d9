"""The recorder node: every message of a namespace into an MCAP (``python -m nodes.recorder``)."""
