"""Insertion into an open fixture: the grasp height rule, the hover height and the admittance.

A box held by two flat palms on its side faces is lowered into an open fixture (four walls on
the table, each ``clearance`` m outside the box's faces). Three formulas live here, once:

* :func:`grasp_height`: how far above the box's centre the palms' centres go, so that their
  lower edges stay ``margin`` above the walls' tops once the box is seated (the palms sit
  just outside the held faces, right above the walls). :func:`max_wall_height` is the tallest
  wall the rule can clear while each palm still covers half its length of the face.
* :func:`hover_height`: how high above its seated pose the box is carried before descending.
* :func:`admittance_step`: the force coupling of the descent. The palms' targets shift in
  the direction the fixture pushes the box (away from a wall it presses), plus towards the
  goal by what the measured box is off it sideways; the descent's phase runs slower as the
  fixture's force grows and stops while it exceeds a bound.

numpy only; SI units, world frame.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from skills.types import Array

#: Gap kept between a palm's lower edge and the walls' tops with the box seated, m.
PALM_WALL_MARGIN_M = 0.01
#: Least share of a palm's length that must press on the held face.
MIN_FACE_COVER = 0.5
#: Height of the box's bottom above the walls' tops where the descent starts, m.
HOVER_ABOVE_WALLS_M = 0.02


def grasp_height(
    box_height: float, palm_length: float, wall_height: float, margin: float = PALM_WALL_MARGIN_M
) -> float:
    """Height of the palms' centres above the box's centre, m (>= 0).

    Parameters
    ----------
    box_height : float
        The box's extent along its z axis, m.
    palm_length : float
        The palm's extent along the face's vertical (its down axis), m.
    wall_height : float
        Height of the fixture's walls above its floor (the box's seated bottom), m; 0 for none.
    margin : float
        Gap left between a palm's lower edge and the walls' tops, m.
    """
    need = wall_height + margin + palm_length / 2.0 - box_height / 2.0
    return max(0.0, float(need)) if wall_height > 0.0 else 0.0


def max_wall_height(
    box_height: float, palm_length: float, margin: float = PALM_WALL_MARGIN_M
) -> float:
    """Tallest wall :func:`grasp_height` clears with each palm still pressing on at least
    :data:`MIN_FACE_COVER` of its length of the face, m (may be negative: none fits)."""
    # Palm centre dz above the box centre covers h/2 - (dz - L/2) of the face: >= c L.
    highest_centre = box_height / 2.0 + palm_length / 2.0 - MIN_FACE_COVER * palm_length
    return float(highest_centre + box_height / 2.0 - palm_length / 2.0 - margin)


def hover_height(wall_height: float, above: float = HOVER_ABOVE_WALLS_M) -> float:
    """How far above its seated pose the box's centre is carried before it descends, m."""
    return float(wall_height + above)


@dataclass(frozen=True)
class AdmittanceGains:
    """Gains of :func:`admittance_step`.

    Attributes
    ----------
    compliance : float
        Sideways speed of the palms' targets per newton the fixture pushes the box with,
        m/(s N).
    centring : float
        Sideways speed per metre the measured box is off the goal, 1/s.
    soft_force_n : float
        Fixture force (N) above which the descent slows.
    stop_force_n : float
        Fixture force (N) at and above which the descent stops.
    max_speed : float
        Largest sideways speed of the targets, m/s.
    """

    compliance: float
    centring: float
    soft_force_n: float
    stop_force_n: float
    max_speed: float = 0.02

    def __post_init__(self) -> None:
        if not (self.compliance >= 0 and self.centring >= 0 and self.max_speed > 0):
            raise ValueError(
                "AdmittanceGains: expected compliance, centring >= 0 and max_speed > 0, got "
                f"{self.compliance}, {self.centring}, {self.max_speed}"
            )
        if not 0 <= self.soft_force_n < self.stop_force_n:
            raise ValueError(
                "AdmittanceGains: expected 0 <= soft_force_n < stop_force_n, got "
                f"{self.soft_force_n} and {self.stop_force_n}"
            )


def descent_rate(force_norm: ArrayLike, gains: AdmittanceGains) -> Array:
    """Share of the learnt descent's speed kept under a fixture force of ``force_norm`` N:
    1 below ``soft_force_n``, falling linearly to 0 at ``stop_force_n``; shape of the input."""
    f = np.asarray(force_norm, dtype=float)
    span = gains.stop_force_n - gains.soft_force_n
    return np.clip((gains.stop_force_n - f) / span, 0.0, 1.0)


def shift_velocity(force: ArrayLike, error: ArrayLike, gains: AdmittanceGains) -> Array:
    """Sideways velocity of the palms' targets, (..., 2) m/s, world x and y.

    ``force`` (..., 3) N is what the fixture exerts on the box, world frame (a wall pressing
    the box pushes it away from the wall: the targets follow); ``error`` (..., 2) m is the goal
    minus the measured box, sideways. The sum is capped at ``max_speed``.
    """
    f = np.asarray(force, dtype=float)[..., :2]
    v = gains.compliance * f + gains.centring * np.asarray(error, dtype=float)
    speed = np.linalg.norm(v, axis=-1, keepdims=True)
    return v * np.minimum(1.0, gains.max_speed / np.maximum(speed, 1e-12))


def admittance_step(
    offset: ArrayLike,
    force: ArrayLike,
    error: ArrayLike,
    gains: AdmittanceGains,
    dt: float,
) -> tuple[Array, float]:
    """One control step of the coupling: the targets' new sideways offset (2,) m and the
    share of the descent's phase to advance (:func:`descent_rate` of the force's norm).

    Parameters
    ----------
    offset : array_like, shape (2,)
        The palms' targets' sideways shift so far, world x and y, m.
    force : array_like, shape (3,)
        Force of the fixture on the box, world frame, N.
    error : array_like, shape (2,)
        Goal minus measured box position, world x and y, m.
    gains : AdmittanceGains
    dt : float
        Control period, s.
    """
    v = shift_velocity(force, error, gains)
    rate = float(descent_rate(np.linalg.norm(np.asarray(force, dtype=float)), gains))
    return np.asarray(offset, dtype=float) + v * dt, rate


__all__ = [
    "HOVER_ABOVE_WALLS_M",
    "MIN_FACE_COVER",
    "PALM_WALL_MARGIN_M",
    "AdmittanceGains",
    "admittance_step",
    "descent_rate",
    "grasp_height",
    "hover_height",
    "max_wall_height",
    "shift_velocity",
]
