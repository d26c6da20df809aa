"""The coupling-term protocol: a behaviour as an additive acceleration on a pose DMP.

A coupling term looks at the DMP's current full state and target and returns accelerations
that the DMP adds to its transformation system (the ``tau^2 c`` of :mod:`skills.dmp`). A DMP
takes any number of them and sums them. The learnt RBF forcing term
(:class:`skills.couplings.LearntForcing`) is one; obstacle avoidance, grasp maintenance and
limit repulsion are others.

Each term of the library owns its maths once, twice written: ``acceleration`` is its numpy
reference (vectorised over points and obstacles: what the tests hold the kernels to), and
``pack`` puts its parameters into a composition's program (:mod:`skills.program`) for its
compiled kernel, which is what a composition runs. A term of your own needs only
``acceleration``: the composer evaluates it before each compiled step.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from skills.state import PoseState, PoseTarget
from skills.types import Array


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


@dataclass(frozen=True)
class Weighted:
    """A coupling term scaled by a composition weight (the paper's ``w_j`` / ``w_k``)."""

    term: CouplingTerm
    weight: float

    def acceleration(self, state: PoseState, target: PoseTarget) -> tuple[Array, Array]:
        """``weight`` times the term's accelerations."""
        lin, ang = self.term.acceleration(state, target)
        return self.weight * lin, self.weight * ang


def sum_couplings(
    couplings: Sequence[CouplingTerm], state: PoseState, target: PoseTarget
) -> tuple[Array, Array]:
    """Sum of the coupling accelerations ``(3,), (3,)`` at ``state``."""
    lin = np.zeros(3)
    ang = np.zeros(3)
    for c in couplings:
        a_lin, a_ang = c.acceleration(state, target)
        lin += a_lin
        ang += a_ang
    return lin, ang
