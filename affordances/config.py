"""The reasoner's tunable numbers, with the reason for each default."""

from __future__ import annotations

import math
from dataclasses import dataclass

from affordances.context import check_non_negative, check_positive

#: Standard gravity, m/s^2.
GRAVITY = 9.81


@dataclass(frozen=True)
class ReasonerConfig:
    """Numbers the hard constraints and the scene checks use.

    Attributes
    ----------
    safety_factor : float
        ``k`` in ``2 * mu * F_squeeze >= k * m * g``: margin for accelerations while
        transporting and for friction uncertainty (> 0, default 1.5).
    gravity : float
        Gravitational acceleration, m/s^2, >= 0 (:meth:`under` a world's).
    one_hand_width_factor : float
        One hand holds objects up to this many palm widths across (fingers and thumb wrap
        around roughly twice the palm width), default 2.0.
    min_contact_height_factor : float
        A lateral squeeze needs faces at least this many palm widths tall, so the palm lies
        flat on the face instead of on an edge, default 0.5.
    path_margin_m : float
        An obstacle closer than this to the object's swept path adds obstacle steering, m.
    link_margin_m : float
        An obstacle closer than this to the predicted arm links adds link avoidance, m.
    yaw_tolerance_rad : float
        Goal yaw differences below this need no ``rotate_z``, radians.
    carry_lift_m : float
        How high a carry may lift the object above its rest height, m: the scene checks
        sweep the object's and the arms' paths from rest height up to it (the learnt
        pick-and-place rises about 8 cm over a short move).
    """

    safety_factor: float = 1.5
    gravity: float = GRAVITY
    one_hand_width_factor: float = 2.0
    min_contact_height_factor: float = 0.5
    path_margin_m: float = 0.05
    link_margin_m: float = 0.05
    yaw_tolerance_rad: float = math.radians(5.0)
    carry_lift_m: float = 0.12

    @classmethod
    def under(cls, gravity: float) -> ReasonerConfig:
        """The defaults under a world's ``gravity`` along z, m/s^2 (negative: down)."""
        return cls(gravity=abs(float(gravity)))

    def __post_init__(self) -> None:
        # Zero gravity is a world's to choose (nothing then weighs anything to hold).
        object.__setattr__(
            self, "gravity", check_non_negative(self.gravity, "ReasonerConfig", "gravity")
        )
        for name in (
            "safety_factor",
            "one_hand_width_factor",
            "min_contact_height_factor",
            "path_margin_m",
            "link_margin_m",
            "yaw_tolerance_rad",
            "carry_lift_m",
        ):
            object.__setattr__(
                self, name, check_positive(getattr(self, name), "ReasonerConfig", name)
            )
