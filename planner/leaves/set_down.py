"""Setting an object down by feel: when the palms carry it, and lowering the state that holds it.

The one home of what Transport (placing at a goal), Insert (seating in a fixture) and Release
(letting go, which first sets down an object the palms still carry) share.
"""

from __future__ import annotations

from dataclasses import replace
from typing import cast

import numpy as np

from planner.port import ObjectSensing, PalmControl, offers
from skills.composer import DualArmState
from skills.flip import vertical_half_extent
from skills.vocabulary import ARMS

#: Below this share of the object's stated weight, the palms' summed upward force
#: (:meth:`~planner.port.PalmControl.palm_load`) says a surface carries (part of) the object:
#: an object of half its stated mass, hanging, still loads the palms with 0.5 of it.
SUPPORTED_LOAD_FRACTION = 0.4
#: How fast the palms lower an object no surface carries yet, m/s.
SET_DOWN_SPEED_M_S = 0.02
#: A resting object found further than this from the height the world states for its table
#: rests on something else (another object), not on a table off its stated height, m.
TABLE_FOUND_WITHIN_M = 0.05
#: A table found less than this off its stated height is taken as stated, m: contact
#: settling and a squeeze shift a resting object by a millimetre or so, and the set-down by
#: feel takes up a few millimetres anyway.
TABLE_FOUND_FROM_M = 0.005


def supported_below_n(world: ObjectSensing, name: str) -> float:
    """The palms' summed upward force (N) below which a surface carries (part of) ``name``:
    :data:`SUPPORTED_LOAD_FRACTION` of its stated weight."""
    return SUPPORTED_LOAD_FRACTION * world.object_context(name).mass_kg * world.gravity()


def palm_load_n(world: PalmControl, name: str) -> float:
    """The palms' summed upward force on ``name``, N."""
    return sum(world.palm_load(arm, name) for arm in ARMS)


def table_found_dz(world: ObjectSensing, name: str) -> float:
    """How much higher (m, negative: lower) than the world states it the table top is that
    ``name`` rests on now, found from the object as measured: its lowest point over the stated
    top. 0 when the palms carry it (:func:`supported_below_n`), when it is less than
    :data:`TABLE_FOUND_FROM_M` off, or more than :data:`TABLE_FOUND_WITHIN_M` (it rests on
    something else).

    Where ``world`` has no palms (:class:`~planner.port.PalmControl`), the object is taken
    as resting."""
    palms = cast(PalmControl, world)
    if offers(world, PalmControl) and palm_load_n(palms, name) > supported_below_n(world, name):
        return 0.0
    pose = world.object_pose(name)
    extents = world.object_extents(name)
    lower, _ = world.workspace_bounds(name)
    stated_top = float(lower[2]) - float(extents[2]) / 2.0
    dz = float(pose.position[2] - vertical_half_extent(extents, pose.orientation)) - stated_top
    return dz if TABLE_FOUND_FROM_M <= abs(dz) <= TABLE_FOUND_WITHIN_M else 0.0


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
