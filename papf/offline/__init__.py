"""Offline simulation, no processes: the closed loops of ``papf plan`` and the experiments
(unicycle 2-D, point 3-D, Wang's fixed step, car on a road) and random worlds."""
