"""The terminal: progress lines of long work (used by every room above)."""
