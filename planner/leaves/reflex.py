"""The obstacle reflex: a held or squeezed object that strays near an obstacle, as measured,
or closes on one fast, is pushed back out by shifting both palms' targets away from it.

The motions that carry or close on an object run open loop (a composition checked, then run),
and the palms trail their targets by 1 to 2 cm as they start and stop, more under Hard mode's
actuator faults, and a palm that meets its face first shoves the object until the other
arrives. Transport and Grasp both add this shift to their commands, and their compositions
run on. Transport hands on its composition's state, the shift decaying once the object is
clear; Grasp hands on the palms where they were sent, shift included, so the carry that
follows does not pull the object back towards the obstacle.

The reflex acts on the gap the object will have when its shift takes hold: the measured gap
less what the object's measured velocity towards the obstacle closes in
:data:`REFLEX_HORIZON_S`. Under Hard mode's lagging actuators a held parcel rings at about
10 Hz, +-7 mm at 0.4 m/s, and a shove from a palm that met its face first travels at 0.1 m/s:
either crosses the 1 cm band in a few control steps, faster than a shift that waited for the
band could follow. Only closing speed counts: an object moving away is not pushed further.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from planner.port import ObjectSensing, ObstacleScene
from skills.types import Array

#: Measured gap to an obstacle under which the object is pushed away from it, m: the
#: clearance the shipped trees' PathClear asks of the predicted path. A carry path checked
#: clear by 1 cm grazed a ball in 7 of 300 Hard trials; only an object that strays into the
#: band feels it.
REFLEX_BAND_M = 0.01
#: Shift of both palms' targets away from the obstacle per metre inside the band.
REFLEX_GAIN = 3.0
#: Largest such shift, m (40 N more on each palm at the default 1000 N/m).
REFLEX_MAX_M = 0.04
#: Time constant the shift follows its want with, s: no jump in the palms' targets.
REFLEX_TAU_S = 0.05
#: How far ahead the gap is judged, s: the object's measured closing speed times this counts
#: as closed already. The shift's own time constant: by then the shift has mostly taken hold.
REFLEX_HORIZON_S = REFLEX_TAU_S


class _Sensed(ObjectSensing, ObstacleScene, Protocol):
    """What the reflex reads: the object's motion and its gap to the obstacles."""


def reflex_shift(world: _Sensed, name: str, shift: Array, dt: float) -> Array:
    """The next shift of both palms' targets, (3,) m, that pushes object ``name``, as
    measured, out of :data:`REFLEX_BAND_M` of the nearest obstacle: :data:`REFLEX_GAIN` times
    its depth in the band, along the way out, at most :data:`REFLEX_MAX_M`, followed from
    ``shift`` (3,) m over the control step ``dt`` s with :data:`REFLEX_TAU_S` (and back to
    none once clear). The gap judged is the one :data:`REFLEX_HORIZON_S` ahead at the
    object's measured speed towards the obstacle (none when it moves away)."""
    velocity = np.asarray(world.object_twist(name), dtype=float)[:3]
    gap = world.obstacle_gap(
        name, REFLEX_BAND_M + REFLEX_HORIZON_S * float(np.linalg.norm(velocity))
    )
    want: Array = np.zeros(3)
    if gap is not None:
        away = np.asarray(gap.away, dtype=float)
        closing = max(0.0, -float(velocity @ away))
        depth = REFLEX_BAND_M - (gap.distance_m - REFLEX_HORIZON_S * closing)
        if depth > 0.0:
            want = away * min(REFLEX_GAIN * depth, REFLEX_MAX_M)
    rate = min(1.0, dt / REFLEX_TAU_S)
    return np.asarray(shift + rate * (want - shift), dtype=float)
