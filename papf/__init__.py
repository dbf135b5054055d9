"""papf-stack: the launcher, CLI and transport around the nodes (see README.md)."""

__version__ = "0.2.0"
