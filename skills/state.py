"""The state a pose DMP runs on, and the target it runs to: the unit of handover between skills.

Below every other skills module: the DMPs, the coupling terms and the composer all read these
two types, and none of them needs the others to do so.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import pairwise
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from skills import quaternion as quat
from skills.types import Array


def validated_pose(position: ArrayLike, orientation: ArrayLike) -> tuple[Array, Array]:
    """``position`` as 3 finite floats and ``orientation`` as one unit quaternion (4,).

    Raises
    ------
    ValueError
        Naming the argument, what was expected and what was received.
    """
    y = np.array(position, dtype=float)
    if y.shape != (3,) or not np.all(np.isfinite(y)):
        raise ValueError(f"position: expected 3 finite numbers, got {position!r}")
    q = quat.as_quaternions(orientation, "orientation")
    if q.shape != (4,):
        raise ValueError(f"orientation: expected one quaternion (4,), got shape {q.shape}")
    return y, q


class PoseState(NamedTuple):
    """Full state of a pose DMP, the unit of handover between skills.

    Immutable (a named tuple: it is created every control step, and cheaply).

    Attributes
    ----------
    position, velocity, acceleration : ndarray, shape (3,)
        World (or parent) frame; m, m/s, m/s^2.
    orientation : ndarray, shape (4,)
        Unit quaternion ``(x, y, z, w)``.
    angular_velocity, angular_acceleration : ndarray, shape (3,)
        rad/s, rad/s^2, same frame as the position.
    phase : float
        Canonical phase in (0, 1].
    """

    position: Array
    velocity: Array
    acceleration: Array
    orientation: Array
    angular_velocity: Array
    angular_acceleration: Array
    phase: float = 1.0

    @staticmethod
    def at_rest(position: ArrayLike, orientation: ArrayLike = quat.IDENTITY) -> PoseState:
        """At ``position`` and ``orientation`` with zero velocities, phase 1."""
        y, q = validated_pose(position, orientation)
        z = np.zeros(3)
        return PoseState(y, z, z.copy(), q, z.copy(), z.copy(), 1.0)

    def twist(self) -> Array:
        """Linear and angular velocity stacked, shape (6,)."""
        return np.concatenate((self.velocity, self.angular_velocity))

    def with_phase(self, s: float) -> PoseState:
        """The same pose and motion at another phase (a fresh skill starts at ``s = 1``)."""
        return self._replace(phase=float(s))


#: A pose state's six arrays end to end: position, velocity, acceleration, orientation,
#: angular velocity, angular acceleration (the layout of :func:`state_values`).
STATE_SIZE = 19
#: Where each of the six arrays starts in :func:`state_values`.
POSITION, VELOCITY, ACCELERATION, ORIENTATION, ANGULAR_VELOCITY, ANGULAR_ACCELERATION = (
    0,
    3,
    6,
    9,
    13,
    16,
)


def state_values(state: PoseState) -> Array:
    """``state``'s six arrays end to end, shape (19,)."""
    return np.concatenate(state[:6])


def _field_slices(at: int) -> tuple[slice, ...]:
    bounds = (0, 3, 6, 9, 13, 16, 19)
    return tuple(slice(at + a, at + b) for a, b in pairwise(bounds))


# Built once: states are cut out of a buffer every control tick.
_STATE_SLICES = {at: _field_slices(at) for at in (0, STATE_SIZE, 2 * STATE_SIZE)}


def state_from(values: Array, phase: float, at: int = 0) -> PoseState:
    """The :class:`PoseState` whose arrays are views of ``values[at:at + 19]``."""
    y, yd, ydd, q, w, wd = _STATE_SLICES.get(at) or _field_slices(at)
    return PoseState(values[y], values[yd], values[ydd], values[q], values[w], values[wd], phase)


@dataclass(frozen=True)
class PoseTarget:
    """Where a pose DMP goes and how fast: start, goal, ``tau`` and the forcing scalings.

    Build with :meth:`skills.pose_model.PoseModel.target` so the scalings match the model.

    Attributes
    ----------
    start_position, goal_position : ndarray, shape (3,)
    start_orientation, goal_orientation : ndarray, shape (4,)
    tau : float
        Temporal scaling, s; the motion takes about ``tau``.
    position_matrix, orientation_matrix : ndarray, shape (3, 3)
        Forcing scalings for this start and goal.
    effective_weights : ndarray, shape (K, 7)
        The model's weights with the scalings folded in, plus a column of ones that yields the
        basis normaliser from the same product: ``psi @ W = [f * sum(psi) / s, sum(psi)]``.
    """

    start_position: Array
    start_orientation: Array
    goal_position: Array
    goal_orientation: Array
    tau: float
    position_matrix: Array
    orientation_matrix: Array
    effective_weights: Array
