"""Doc tooling: the tables and numbers of README.md and docs/ rendered from committed CSVs."""
