"""The stack's nodes, one package each (docs/architecture.md); ``import common`` first sets
what every process of the stack shares before numpy loads (common/__init__.py)."""

import common  # noqa: F401
