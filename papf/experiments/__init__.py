"""Experiments (``papf experiment ...``): many runs of planners on worlds, tabulated.

- :mod:`papf.experiments.energy` — the PAPF paper's 3-run energy experiment (IV-C);
- :mod:`papf.experiments.paper_tests` — the papers' test worlds with every planner, a table
  like PAPF Table 2 and one plot per world;
- :mod:`papf.experiments.random_worlds` — success and collision rates on seeded random worlds;
- :mod:`papf.experiments.trials` — one run (offline or through the stack) as a ``Trial``,
  and the CSV / Markdown / progress helpers the experiments share.

Kept free of imports so that ``papf --help`` stays fast.
"""
