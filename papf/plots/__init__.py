"""Pictures (matplotlib, files only): worlds, paths, the planner's mind, IAPF case figures.
They take worlds, arrays and results; they never import a simulator or the launcher."""
