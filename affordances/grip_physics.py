"""The lateral grip's friction: what two palms pressing on opposite faces carry.

Friction follows Bullet's default contact model: the coefficient of a contact is the product
of the two bodies' coefficients (``btManifoldResult::calculateCombinedFriction``), clamped
to 10. A two-palm lateral squeeze holds the object by friction alone, so with both palms
pressing with ``F`` the grasp carries the weight when ``2 * mu * F >= k * m * g``.
"""

from __future__ import annotations

import math

from affordances.context import ObjectContext, RobotCapabilities

#: Bullet clamps the combined friction coefficient to this value.
BULLET_MAX_FRICTION = 10.0


def combined_friction(mu_object: float, mu_palm: float) -> float:
    """Friction coefficient of a palm-object contact as Bullet combines it (product, <= 10)."""
    return min(mu_object * mu_palm, BULLET_MAX_FRICTION)


def palm_contact_friction(context: ObjectContext, robot: RobotCapabilities) -> float:
    """Friction coefficient of a palm on the object, from both declared coefficients."""
    return combined_friction(context.friction, robot.palm_friction)


def grip_friction_n(mu: float, squeeze_force_n: float) -> float:
    """Load, N, that two palms pressing with ``squeeze_force_n`` N each carry by friction.

    The lateral grip's law, ``2 * mu * F``: the reasoner's required force and the planner's
    spare acceleration both come from it.
    """
    return 2.0 * mu * squeeze_force_n


def required_squeeze_force(
    mass_kg: float, mu: float, safety_factor: float, gravity: float
) -> float:
    """Normal force per palm, N, for two palms to hold ``safety_factor`` times the weight.

    Solves ``grip_friction_n(mu, F) = k * m * g`` for ``F``; infinite when ``mu`` is 0.
    """
    if mu <= 0.0:
        return math.inf
    return safety_factor * mass_kg * gravity / grip_friction_n(mu, 1.0)


def spare_grip_acceleration(
    context: ObjectContext, robot: RobotCapabilities, squeeze_force_n: float, gravity: float
) -> float:
    """Acceleration, m/s^2, a two-palm squeeze of ``squeeze_force_n`` N per palm can still
    give the object once it carries its weight under ``gravity`` (m/s^2); negative when the
    grip cannot carry it.

    ``(grip_friction_n(mu, F) - m g) / m``, with ``mu`` the palm-object contact's
    (:func:`palm_contact_friction`).
    """
    mu = palm_contact_friction(context, robot)
    weight = context.mass_kg * gravity
    return (grip_friction_n(mu, squeeze_force_n) - weight) / context.mass_kg


__all__ = [
    "BULLET_MAX_FRICTION",
    "combined_friction",
    "grip_friction_n",
    "palm_contact_friction",
    "required_squeeze_force",
    "spare_grip_acceleration",
]
