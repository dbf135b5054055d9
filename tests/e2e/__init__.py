"""Tests: the e2e tier (docs/architecture.md, "Tests")."""
