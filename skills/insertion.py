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
  fixture's force grows (:func:`felt_force`) and stops while it exceeds a bound. A box
  that comes down on a wall's top (the fixture stands off where the robot was told, by more
  than the clearance) is pushed up, not sideways, so the wall gives no direction to yield
  in; there the targets search (:func:`search_velocity`): they slide away from where the
  wall bears on the box's bottom (:func:`bearing_point`, from the fixture's torque about the
  box's centre), towards the open slot, as fast as the upward force has slowed the descent.

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
#: Sideways speed of the search off a wall's top, m/s: a few millimetres of overlap (the
#: fixture off by a little more than its clearance) within a second, slow enough that the box
#: sliding on the wall's top (friction 0.3 of 15 N) stays in the palms' grip.
SEARCH_SPEED_M_S = 0.005
#: Farthest the palms' targets shift sideways from the learnt descent, m: a fixture found
#: farther than this from where the robot was told is not searched for (the paper judge's
#: placement tolerance, 2 cm).
MAX_SHIFT_M = 0.02
#: Upward force of the fixture on the box at which the descent stops, N: a wall's top under
#: the box's bottom edge. The palms' grip yields in rotation about its axis to the friction
#: there (a lever of half the box's height), so the box slides across the top only while
#: it barely rests on it.
TOP_STOP_FORCE_N = 2.0


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
    search_speed : float
        Sideways speed of the search off a wall's top (:func:`search_velocity`) once the
        descent has stopped, m/s; 0: no search.
    max_shift : float
        Farthest the targets shift sideways in all, m.
    top_stop_force_n : float
        Upward force (N) at and above which the descent stops (:func:`felt_force`), > 0.
    """

    compliance: float
    centring: float
    soft_force_n: float
    stop_force_n: float
    max_speed: float = 0.02
    search_speed: float = SEARCH_SPEED_M_S
    max_shift: float = MAX_SHIFT_M
    top_stop_force_n: float = TOP_STOP_FORCE_N

    def __post_init__(self) -> None:
        if not (
            self.compliance >= 0
            and self.centring >= 0
            and self.search_speed >= 0
            and self.max_speed > 0
            and self.max_shift >= 0
            and self.top_stop_force_n > 0
        ):
            raise ValueError(
                "AdmittanceGains: expected compliance, centring, search_speed, max_shift >= 0 "
                f"and max_speed, top_stop_force_n > 0, got {self.compliance}, {self.centring}, "
                f"{self.search_speed}, {self.max_shift}, {self.max_speed}, "
                f"{self.top_stop_force_n}"
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


def felt_force(force: ArrayLike, gains: AdmittanceGains) -> Array:
    """The fixture's force as the descent feels it, (...,) N: its norm, or its upward part
    times ``stop_force_n / top_stop_force_n`` where that is larger.

    A wall's face pushing the box sideways is what the judge bounds, and the descent stops at
    ``stop_force_n`` of it. A wall's top bears up on the box's bottom edge instead, away from
    the palms' grasp axis: the friction there turns the box in the palms' grip (their
    orientation springs are soft) rather than let it slide across towards the slot, unless the
    box barely rests, so the descent stops at ``top_stop_force_n`` upwards.
    """
    f = np.asarray(force, dtype=float)
    up = np.maximum(f[..., 2], 0.0) * (gains.stop_force_n / gains.top_stop_force_n)
    return np.asarray(np.maximum(np.linalg.norm(f, axis=-1), up))


def bearing_point(force: ArrayLike, torque: ArrayLike) -> Array:
    """Where the fixture bears up on the box, sideways from the box's centre, (..., 2) m,
    world x and y: the centre of pressure of the upward force (zeros where it pushes not up).

    ``force`` (..., 3) N and ``torque`` (..., 3) N m are the fixture's on the box, world
    frame, the torque about the box's centre. An upward ``f_z`` at ``r`` gives
    ``torque = (r_y f_z, -r_x f_z, 0)``, so ``r = (-torque_y, torque_x) / f_z``.
    """
    f = np.asarray(force, dtype=float)
    t = np.asarray(torque, dtype=float)
    up = f[..., 2:3]
    r = np.stack([-t[..., 1], t[..., 0]], axis=-1)
    return np.where(up > 1e-9, r / np.maximum(up, 1e-9), 0.0)


def search_velocity(force: ArrayLike, torque: ArrayLike, gains: AdmittanceGains) -> Array:
    """Sideways velocity of the search off a wall's top, (..., 2) m/s, world x and y.

    Away from :func:`bearing_point` (the box's edge resting on the wall: the slot is on the
    other side), at ``search_speed`` times the share of the descent the upward force has
    stopped (``1 -`` :func:`descent_rate` of :func:`felt_force` of ``f_z``): none while the
    box hangs free or slides down a wall's face.
    """
    r = -bearing_point(force, torque)
    unit = r / np.maximum(np.linalg.norm(r, axis=-1, keepdims=True), 1e-12)
    up = np.zeros_like(np.asarray(force, dtype=float))
    up[..., 2] = np.asarray(force, dtype=float)[..., 2]
    stopped = 1.0 - descent_rate(felt_force(up, gains), gains)[..., None]
    return gains.search_speed * stopped * unit


def shift_velocity(
    force: ArrayLike,
    error: ArrayLike,
    gains: AdmittanceGains,
    torque: ArrayLike | None = None,
) -> Array:
    """Sideways velocity of the palms' targets, (..., 2) m/s, world x and y.

    ``force`` (..., 3) N is what the fixture exerts on the box, world frame (a wall pressing
    the box pushes it away from the wall: the targets follow); ``error`` (..., 2) m is the goal
    minus the measured box, sideways; ``torque`` (..., 3) N m, the fixture's about the box's
    centre, adds the search off a wall's top (:func:`search_velocity`; None: no search). The
    sum is capped at ``max_speed``.
    """
    f = np.asarray(force, dtype=float)
    v = gains.compliance * f[..., :2] + gains.centring * np.asarray(error, dtype=float)
    if torque is not None:
        v = v + search_velocity(f, torque, gains)
    speed = np.linalg.norm(v, axis=-1, keepdims=True)
    return v * np.minimum(1.0, gains.max_speed / np.maximum(speed, 1e-12))


def admittance_step(
    offset: ArrayLike,
    force: ArrayLike,
    error: ArrayLike,
    gains: AdmittanceGains,
    dt: float,
    torque: ArrayLike | None = None,
) -> tuple[Array, float]:
    """One control step of the coupling: the targets' new sideways offset (2,) m (within
    ``max_shift`` of none) and the share of the descent's phase to advance
    (:func:`descent_rate` of :func:`felt_force`).

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
    torque : array_like, shape (3,), optional
        Torque of the fixture about the box's centre, world frame, N m: the search off a
        wall's top (:func:`search_velocity`). None: no search.
    """
    v = shift_velocity(force, error, gains, torque)
    rate = float(descent_rate(felt_force(force, gains), gains))
    shifted = np.asarray(offset, dtype=float) + v * dt
    norm = float(np.linalg.norm(shifted))
    if norm > gains.max_shift:
        shifted = shifted * (gains.max_shift / norm)
    return shifted, rate


__all__ = [
    "HOVER_ABOVE_WALLS_M",
    "MAX_SHIFT_M",
    "MIN_FACE_COVER",
    "PALM_WALL_MARGIN_M",
    "SEARCH_SPEED_M_S",
    "TOP_STOP_FORCE_N",
    "AdmittanceGains",
    "admittance_step",
    "bearing_point",
    "descent_rate",
    "felt_force",
    "grasp_height",
    "hover_height",
    "max_wall_height",
    "search_velocity",
    "shift_velocity",
]
