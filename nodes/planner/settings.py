"""Declared type and valid range of every planner parameter (see :mod:`common.params`).

The shared table (:data:`APF`, for :class:`~nodes.planner.field.APFParams`) and the node's
own (:data:`NODE`); each planner's table lies in its folder and its strategy declares it
as ``SPECS``. Safety parameters (``safety=True``) keep avoidance and the speed limits on;
the charges' ranges fix eq. 2's signs, ``q_V, q_O, q_Q < 0 < q_G`` (docs/planners.md,
"The algorithms in the code"). Used by the registry's checks of every setting.
"""

from __future__ import annotations

from common.drive import PAIR_TIMEOUT
from common.errors import ConfigError
from common.params import FLAG, Spec, integer, num, pos
from common.robot import LIDAR_RANGE_MAX_M, V_MAX_M_S, W_MAX_RAD_S

MAX_BEAMS = 100_000      # [-] LiDAR points a planner is configured for
MAX_GAIN = 1e4           # [-] largest force constant (defaults are 1 .. 10)

# Safety floors, measured (docs/planners.md "Safety floors", docs/data/safety-floor.csv:
# `papf experiment safety-floor`, offline on energy-blocking and papf-test-1): each the
# smallest swept value at which no run of any planner collided, the others at their
# defaults. A value just above zero switches avoidance off as surely as zero does.
D_O_MIN_M = 0.25         # [m] repulsion range (0.2 collided on both worlds)
K_VO_L_MIN = 1.0         # [-] k_VO * L (0.5 collided: PAPF on both worlds)
CHARGE_MIN = 0.2         # [-] |q_V|, |q_O| (0.1 collided: PAPF on energy-blocking)
# The single floors do not compose: eq. 2 repels with the product k_VO q_V q_O, so it has a
# floor of its own (each factor at its floor would be 250 times weaker than the default).
REPULSION_MIN = 2.0      # [-] k_vo_l * q_v * q_o (1 collided: q_o = -0.1 with PAPF)
# The floors of a planner's own settings are in its folder's settings.py (arapf, wang).

# The other side of the balance, measured the same way upwards (`papf experiment safety-floor
# --attraction`, docs/data/safety-attraction.csv): a goal pull that outweighs the obstacles'
# push drives the robot into what lies on the line as surely as a weak push.
K_VG_MAX = 50.0          # [-] k_VG (75 collided: PAPF on papf-test-1; 100 on both worlds)
Q_G_MAX = 10.0           # [-] q_G (50 collided: APF and PAPF)
# The gains do not act alone: eq. 2 weighs k_VG q_G against k_VO L |q_O| (q_V is in both), so
# their ratio has a ceiling of its own, reached at the repulsion floor too (k_vo_l = 2).
ATTRACTION_RATIO_MAX = 5.0   # [-] k_vg q_g / (k_vo_l |q_o|) (7.5 collided: PAPF, k_vg = 75)

APF: dict[str, Spec] = {
    "lidar_points": integer(1, MAX_BEAMS),
    "q_v": num(-100.0, -CHARGE_MIN, safety=True),
    "q_o": num(-100.0, -CHARGE_MIN, safety=True),
    "q_g": num(0.0, Q_G_MAX, lo_open=True, safety=True),
    "k_vg": pos(K_VG_MAX, safety=True),
    "k_vo_l": num(K_VO_L_MIN, MAX_GAIN, safety=True),
    "d_o": num(D_O_MIN_M, LIDAR_RANGE_MAX_M, "m", safety=True),
    "theta_err_max_deg": pos(180.0, "deg"),
    "v_max": pos(V_MAX_M_S, "m/s", safety=True),
    "k_theta": pos(100.0, "1/s"),
    "w_max": pos(W_MAX_RAD_S, "rad/s", safety=True),
    "scale_to_scan": FLAG,
    "stagnation_window_s": pos(3600.0, "s"),
    "stagnation_progress_m": pos(10.0, "m"),
    "stagnation_roam_m": pos(100.0, "m"),
    "stagnation_max_s": pos(86_400.0, "s"),
}

# The planner node's own options (python -m nodes.planner): the stale-input stop is a
# safety setting — past 2 s a robot drives on data that no longer describes the world.
NODE: dict[str, Spec] = {
    "stale_timeout": pos(2.0, "s", safety=True),
    "pair_timeout": PAIR_TIMEOUT,
    # the short plan each realtime command carries (docs/link-driving.md): the robot follows
    # it at most this far; 0.2 s is two scan periods, 2 s the watchdog's own ceiling
    "plan_horizon": num(0.2, 2.0, "s"),
}


def attraction_ratio(apf, algo=None) -> float:
    """The goal's pull over the obstacles' push, from the gains alone: eq. 2's
    ``k_VG q_G / (k_VO L |q_O|)`` (``q_V`` is in both), or for a planner whose own parameters
    have ``k_att`` and ``k_rep_l`` (Wang's eqs. 6-8) ``k_att / k_rep_l``."""
    if algo is not None and hasattr(algo, "k_att") and hasattr(algo, "k_rep_l"):
        return algo.k_att / algo.k_rep_l
    return apf.k_vg * apf.q_g / (apf.k_vo_l * abs(apf.q_o))


def check_strength(apf) -> None:
    """eq. 2's repulsion product ``k_vo_l*q_v*q_o`` above its floor (:data:`REPULSION_MIN`);
    ConfigError, one line. A strategy adds its own products in ``Strategy.check_strength``."""
    require_product("k_vo_l*q_v*q_o", apf.k_vo_l * apf.q_v * apf.q_o, REPULSION_MIN)
    require_ratio("k_vg*q_g/(k_vo_l*|q_o|)", attraction_ratio(apf), ATTRACTION_RATIO_MAX)


def require_ratio(name: str, value: float, ceiling: float) -> None:
    """ConfigError (one line) unless the attraction-to-repulsion ratio ``value`` is at most
    ``ceiling``."""
    if not value <= ceiling:
        raise ConfigError(f"{name} = {value:g}: the goal's pull may be at most {ceiling:g} times "
                          "the obstacles' push (above it the robot drives into obstacles; "
                          "docs/planners.md \"Safety floors\")")


def require_product(name: str, value: float, floor: float) -> None:
    """ConfigError (one line) unless the repulsion product ``value`` is at least ``floor``."""
    if not value >= floor:
        raise ConfigError(f"{name} = {value:g}: the obstacle repulsion must be at least "
                          f"{floor:g} (below it the robot collides; docs/planners.md "
                          "\"Safety floors\")")
