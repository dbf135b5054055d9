"""Offline simulation, no processes: :func:`papf.offline.run.simulate`, the one entry point of
``papf plan`` and the experiments, over the motion models (unicycle 2-D, point 3-D, Wang's
fixed step, car on a road); and random worlds (:mod:`papf.offline.world_gen`)."""
