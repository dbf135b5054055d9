"""Subcommands contributed by feature packages: each exposes ``register(subparsers)``."""

from __future__ import annotations

REGISTRARS: list = []
