"""The coupling-term protocol: a behaviour as an additive acceleration on a pose DMP.

A coupling term looks at the DMP's current full state and target and returns accelerations
that the DMP adds to its transformation system (the ``tau^2 c`` of :mod:`skills.dmp`). A DMP
takes any number of them and sums them. The learnt RBF forcing term
(:class:`skills.pose_dmp.LearntForcing`) is one; obstacle avoidance, grasp maintenance and
limit repulsion are others.

A term that runs every control tick may also give the same accelerations as six floats from a
state read once as floats (:class:`ScalarCouplingTerm`): on 3-vectors numpy's per-call cost
exceeds the arithmetic, and the dual-arm composer sums its terms in floats.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Protocol, runtime_checkable

from skills.types import Array

if TYPE_CHECKING:
    from skills.pose_dmp import PoseFloats, PoseState, PoseTarget

#: Linear (m/s^2) then angular (rad/s^2) acceleration, as floats.
AccelerationFloats = tuple[float, float, float, float, float, float]

ZERO_ACCELERATION: AccelerationFloats = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


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


@runtime_checkable
class ScalarCouplingTerm(CouplingTerm, Protocol):
    """A coupling term that also gives its accelerations as floats (the per-tick path)."""

    def scalar_acceleration(self, pose: PoseFloats, target: PoseTarget) -> AccelerationFloats:
        """:meth:`acceleration` at ``pose.source``, from its values read as floats."""
        ...


#: A term's accelerations as floats: ``(pose, target) -> AccelerationFloats``.
ScalarTerm = Callable[["PoseFloats", "PoseTarget"], AccelerationFloats]
#: A scalar term and its composition weight.
WeightedScalar = tuple[ScalarTerm, float]


def scalar_evaluation(term: CouplingTerm) -> ScalarTerm:
    """The term's accelerations as floats: its scalar path, else its arrays read as floats."""
    if isinstance(term, ScalarCouplingTerm):
        return term.scalar_acceleration

    def read(pose: PoseFloats, target: PoseTarget) -> AccelerationFloats:
        lin, ang = term.acceleration(pose.source, target)
        l0, l1, l2 = lin.tolist()
        r0, r1, r2 = ang.tolist()
        return (l0, l1, l2, r0, r1, r2)

    return read


def add_scalar_terms(
    acc: list[float], terms: Sequence[WeightedScalar], pose: PoseFloats, target: PoseTarget
) -> None:
    """Add each term's weighted accelerations at ``pose`` to ``acc`` (6 floats), in order."""
    for evaluate, weight in terms:
        a = evaluate(pose, target)
        if weight != 1.0:
            a = (
                weight * a[0],
                weight * a[1],
                weight * a[2],
                weight * a[3],
                weight * a[4],
                weight * a[5],
            )
        acc[0] += a[0]
        acc[1] += a[1]
        acc[2] += a[2]
        acc[3] += a[3]
        acc[4] += a[4]
        acc[5] += a[5]
