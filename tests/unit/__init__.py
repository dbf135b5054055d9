"""Tests: the unit tier (docs/architecture.md, "Tests")."""
