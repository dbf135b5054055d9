"""papf-stack: the launcher, CLI and transport around the nodes (see README.md)."""

from common import __version__  # the one version (common/__init__.py)

__all__ = ["__version__"]
