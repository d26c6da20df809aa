"""Level carry: how fast and how tilted a tray may be carried without losing a loose ball.

The one formula (:func:`max_carry_acceleration`) bounds the tray's horizontal acceleration by
what keeps a ball on it; :func:`level_carry_tau` turns that bound into the shortest duration
of a minimum-jerk carry (the level-carry skill is learnt from a minimum-jerk demonstration,
``demos/level_carry.csv``). Frames: the tray's floor is level in the world when the tray is;
accelerations are along the floor, m/s^2; angles in radians.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

#: Peak acceleration of a minimum-jerk profile over distance ``D`` in time ``T`` is
#: ``MIN_JERK_PEAK * D / T**2`` (the profile ``D (10 s^3 - 15 s^4 + 6 s^5)``, peak at
#: ``s = 1/2 -+ sqrt(3)/6``).
MIN_JERK_PEAK = 10.0 / math.sqrt(3.0)

#: The share of a level carry's duration spent moving across (the rest lifts and lowers): the
#: demonstration's (``demos/generate.py``, ``level_carry``), which the learnt skill keeps.
CARRY_SHARE = 0.7

#: The judge's bound on the tray's tilt, rad (issue 19: at most 5 degrees).
MAX_TILT_RAD = math.radians(5.0)


@dataclass(frozen=True)
class LooseBall:
    """A ball lying loose in a rimmed tray, as the level carry needs it.

    Attributes
    ----------
    radius_m : float
        The ball's radius, m (> 0).
    rim_m : float
        Height of the rim's top above the floor the ball rolls on, m (> 0).
    room_m : float
        Longest straight roll on the floor from wall to wall, m: the inner length less the
        ball's diameter (>= 0).
    """

    radius_m: float
    rim_m: float
    room_m: float

    def __post_init__(self) -> None:
        if not (self.radius_m > 0 and self.rim_m > 0 and self.room_m >= 0):
            raise ValueError(
                "LooseBall: expected radius_m > 0, rim_m > 0 and room_m >= 0, got "
                f"{self.radius_m!r}, {self.rim_m!r}, {self.room_m!r}"
            )


def max_carry_acceleration(
    ball: LooseBall, tilt_rad: float = MAX_TILT_RAD, gravity: float = 9.81
) -> float:
    """The largest horizontal acceleration of the tray that keeps ``ball`` on it, m/s^2.

    A solid ball rolling without slipping on a floor tilted by ``theta`` and accelerated by
    ``a`` is pushed along the floor by ``f = g sin(theta) + a cos(theta)`` per unit mass (in
    the tray's frame). It leaves over the rim in one of two ways:

    - statically, when the rim is lower than the ball's radius: pressed on the rim's top edge,
      it rolls over once the floor-parallel push leans past the edge, ``f / g > tan(alpha)``
      with ``cos(alpha) = (r - h) / r`` (a rim at least as high as the radius holds it at any
      lean below 90 degrees);
    - dynamically: rolling freely across the floor's ``room`` from one wall to the other, it
      gains ``m f room`` of kinetic energy (the work of ``f``; rotation included), and getting
      over the rim lifts its centre by ``h`` against gravity, ``m g h``. Without counting the
      energy the impact loses, it stays on while ``f room <= g h``.

    So ``a <= min(g h / room, g tan(alpha)) / cos(theta) - g tan(theta)``, at the worst tilt
    ``theta = tilt_rad``. Zero if the tilt alone would lose the ball.

    Parameters
    ----------
    ball : LooseBall
    tilt_rad : float
        The largest tilt of the tray allowed, rad.
    gravity : float
        Magnitude of gravity, m/s^2.

    Returns
    -------
    float
        Bound on the horizontal acceleration, m/s^2 (inf if nothing bounds it).
    """
    g = abs(float(gravity))
    h, r = ball.rim_m, ball.radius_m
    static = math.inf if h >= r else math.tan(math.acos((r - h) / r))
    dynamic = math.inf if ball.room_m == 0.0 else h / ball.room_m
    push = g * min(static, dynamic)  # the largest floor-parallel push per unit mass
    c, s = math.cos(tilt_rad), math.sin(tilt_rad)
    return max(0.0, (push - g * s) / c)


def level_carry_tau(path_m: float, max_acceleration: float) -> float:
    """Shortest duration of a level carry over ``path_m`` m across whose peak acceleration is
    at most ``max_acceleration`` m/s^2, s (0 if unbounded): a minimum-jerk crossing taking
    :data:`CARRY_SHARE` of the whole."""
    if not (path_m >= 0 and max_acceleration > 0):
        raise ValueError(
            "level_carry_tau: expected path_m >= 0 and max_acceleration > 0, got "
            f"{path_m!r}, {max_acceleration!r}"
        )
    if math.isinf(max_acceleration):
        return 0.0
    return math.sqrt(MIN_JERK_PEAK * path_m / max_acceleration) / CARRY_SHARE


__all__ = [
    "CARRY_SHARE",
    "MAX_TILT_RAD",
    "MIN_JERK_PEAK",
    "LooseBall",
    "level_carry_tau",
    "max_carry_acceleration",
]
