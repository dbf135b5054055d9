"""The numbers of a PAPF cycle in one object, built in one place (:func:`kernel_params`).

Every PAPF kernel (:mod:`nodes.planner.papf.kernels`, :mod:`nodes.planner.papf.compiled`)
and the numpy steps of :mod:`nodes.planner.papf.strategy` read the gains and the derived
counts from a :class:`KernelParams` instead of recomputing them from ``APFParams`` and
``PAPFParams``: eq. 2's two gains, eq. 7's quark gain, Algorithm 1's step counts. It is a
``NamedTuple`` so numba takes it as one argument (a tuple of floats and ints) and reads its
fields by name; the products are formed here in the order the paper writes them
(``k q_V q_X``), the same order as before, so every result is bit for bit unchanged.
"""

from __future__ import annotations

from typing import NamedTuple


class KernelParams(NamedTuple):
    """One PAPF cycle's constants (PAPF paper, Szczepanski et al. 2022, eqs. 2, 7, 8, Alg. 1)."""

    g_goal: float        # k_VG q_V q_G: eq. 2's goal gain
    g_obs: float         # k_VO q_V q_O: eq. 2's obstacle gain (k_VO = 10 / L)
    g_q: float           # k_VQ q_V q_Q with k_VQ = k_vq_factor k_VO: eq. 7's quark gain
    d_o: float           # [m] obstacles' repulsive range
    d_q: float           # [m] the quarks' range in the prediction
    step: float          # [m] Delta, Algorithm 1's step
    i_max: int           # lambda / Delta steps of the prediction
    n_stag: int          # lambda_stag / Delta extra steps of the stagnation check
    stag_radius: float   # [m] R: the tail's radius that means stagnation
    max_quarks: int      # M: repetitions per cycle and quarks in use
    pull_range: float    # [m] the prediction's goal pull at most this far (inf: literal)
    ball: float          # [m] motion law: a quark's charged-ball radius
    tie_tol: float       # [m] eq. 8 ties
    q_lim: float         # [m] motion law: quarks act within this range (d_o, or d_q)


def kernel_params(apf, pp) -> KernelParams:
    """The :class:`KernelParams` of ``apf`` (``APFParams``) and ``pp`` (``PAPFParams``).

    Kept for the next calls: the planner passes the same two objects every cycle until its
    settings change, so this is one identity check per cycle, not fourteen products.
    """
    global _LAST
    last = _LAST   # one read: another thread may replace it meanwhile
    if apf is last[0] and pp is last[1]:
        return last[2]
    kp = KernelParams(
        g_goal=float(apf.k_vg * apf.q_v * apf.q_g), g_obs=float(apf.k_vo * apf.q_v * apf.q_o),
        g_q=float(pp.k_vq_factor * apf.k_vo * apf.q_v * pp.q_q), d_o=float(apf.d_o), d_q=float(pp.d_q),
        step=float(pp.step_m), i_max=int(pp.i_max), n_stag=int(pp.n_stag),
        stag_radius=float(pp.stag_radius), max_quarks=int(pp.max_quarks),
        pull_range=float(pp.pull_range), ball=float(pp.quark_ball_m), tie_tol=float(pp.tie_tol_m),
        q_lim=float(apf.d_o if pp.motion_quarks_within_d_o else pp.d_q))
    _LAST = (apf, pp, kp)
    return kp


_LAST: tuple = (None, None, None)
