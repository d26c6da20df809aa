"""Setting an object down by feel: when the palms carry it, and lowering the state that holds it.

The one home of what Transport (placing at a goal), Insert (seating in a fixture) and Release
(letting go, which first sets down an object the palms still carry) share.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from planner.port import ObjectSensing, PalmControl
from skills.composer import DualArmState
from skills.vocabulary import ARMS

#: Below this share of the object's stated weight, the palms' summed upward force
#: (:meth:`~planner.port.PalmControl.palm_load`) says a surface carries (part of) the object:
#: an object of half its stated mass, hanging, still loads the palms with 0.5 of it.
SUPPORTED_LOAD_FRACTION = 0.4
#: How fast the palms lower an object no surface carries yet, m/s.
SET_DOWN_SPEED_M_S = 0.02


def supported_below_n(world: ObjectSensing, name: str) -> float:
    """The palms' summed upward force (N) below which a surface carries (part of) ``name``:
    :data:`SUPPORTED_LOAD_FRACTION` of its stated weight."""
    return SUPPORTED_LOAD_FRACTION * world.object_context(name).mass_kg * world.gravity()


def palm_load_n(world: PalmControl, name: str) -> float:
    """The palms' summed upward force on ``name``, N."""
    return sum(world.palm_load(arm, name) for arm in ARMS)


def lowered(state: DualArmState, depth_m: float, speed_m_s: float = 0.0) -> DualArmState:
    """``state`` with {O} (and so both palms) ``depth_m`` lower, moving down at ``speed_m_s``;
    a negative depth raises it. The grip in {O} is unchanged."""
    obj = state.object
    velocity = obj.velocity.copy()
    velocity[2] = -speed_m_s
    return replace(
        state,
        object=obj._replace(
            position=obj.position - np.array([0.0, 0.0, depth_m]), velocity=velocity
        ),
    )
