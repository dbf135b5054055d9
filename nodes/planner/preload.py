"""What the launcher's fork server loads before it forks a planner (papf/launch/forkserver.py)."""

from __future__ import annotations


def preload(argv: list[str]) -> None:
    """The named planner's compiled kernels, loaded once for all the run's planners of that
    kind. numba is loaded there as in a process that has scipy (the tracker's and the
    social-force planner's need it): ``lazy.numba_without_scipy`` only spares a planner
    process of its own the import, and the kernels' commands are the same either way
    (tests/unit/test_lazy_numba.py)."""
    from nodes.planner.registry import DEFAULT_PLANNER, PLANNERS, make_planner
    name = argv[argv.index("--planner") + 1] if "--planner" in argv[:-1] else DEFAULT_PLANNER
    if name in PLANNERS:
        make_planner(name).warm_up()
