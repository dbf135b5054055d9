"""Tests: the bus tier (docs/architecture.md, "Tests")."""
