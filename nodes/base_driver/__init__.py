"""base_driver node."""
