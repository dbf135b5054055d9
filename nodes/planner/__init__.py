"""planner node."""
