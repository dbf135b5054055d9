"""Tests: the support tier (docs/architecture.md, "Tests")."""
