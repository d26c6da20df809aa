"""The coupling-term protocol: a behaviour as an additive acceleration on a pose DMP.

A coupling term looks at the DMP's current full state and target and returns accelerations
that the DMP adds to its transformation system (the ``tau^2 c`` of :mod:`skills.dmp`). A DMP
takes any number of them and sums them. The learnt RBF forcing term
(:class:`skills.pose_dmp.LearntForcing`) is one; obstacle avoidance, grasp maintenance and
limit repulsion are others.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol, runtime_checkable

from skills.types import Array

if TYPE_CHECKING:
    from skills.pose_dmp import PoseState, PoseTarget


@runtime_checkable
class CouplingTerm(Protocol):
    """Anything with an ``acceleration(state, target)`` method."""

    def acceleration(self, state: PoseState, target: PoseTarget) -> tuple[Array, Array]:
        """Additive accelerations at ``state``.

        Parameters
        ----------
        state : PoseState
            Current full state (possibly measured).
        target : PoseTarget
            Start, goal and ``tau`` of the running DMP.

        Returns
        -------
        linear : ndarray, shape (3,)
            m/s^2, in the DMP's frame.
        angular : ndarray, shape (3,)
            rad/s^2, in the DMP's frame.
        """
        ...
