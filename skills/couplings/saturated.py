"""A group of coupling terms summed, faded near the end of the motion, and its norms limited.

A held object can only follow accelerations its grip transmits: friction bounds the force the
palms can add. Avoidance terms that grow without bound near an obstacle (a ``1/p^2``
potential) are summed here and scaled down as a whole when the sum exceeds the limits,
keeping its direction. In a composition's program a group is a GROUP row, its terms' rows,
and a SATURATE row that the interpreter applies to their sum.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from skills.couplings.term import CouplingTerm, Weighted, sum_couplings
from skills.kernel import kernel
from skills.program import Kind, Packer
from skills.state import PoseState, PoseTarget
from skills.types import Array

#: Below this gate the faded sum is zero.
_GATE_OFF = 0.05


class Saturated:
    """The weighted sum of several coupling terms, its norms limited.

    Parameters
    ----------
    terms : sequence of (CouplingTerm, weight)
    max_linear : float
        m/s^2.
    max_angular : float
        rad/s^2.
    fade_phase : float
        Below this phase the sum fades as ``(s / fade_phase)^2``, to zero by a phase about
        a fifth of it (0: never fades).
    """

    def __init__(
        self,
        terms: Sequence[tuple[CouplingTerm, float]],
        max_linear: float,
        max_angular: float,
        fade_phase: float = 0.0,
    ) -> None:
        if not (max_linear > 0 and max_angular > 0):
            raise ValueError(
                f"max_linear, max_angular: expected positive limits, got {max_linear}, "
                f"{max_angular}"
            )
        if not 0.0 <= fade_phase < 1.0:
            raise ValueError(f"fade_phase: expected a phase in [0, 1), got {fade_phase}")
        self.terms = tuple(Weighted(t, float(w)) for t, w in terms)
        self.max_linear = float(max_linear)
        self.max_angular = float(max_angular)
        self.fade_phase = float(fade_phase)

    def acceleration(self, state: PoseState, target: PoseTarget) -> tuple[Array, Array]:
        """The limited sum (linear m/s^2, angular rad/s^2), faded out below ``fade_phase``."""
        gate = fade_gate(state.phase, self.fade_phase)
        if gate == 0.0:
            # Like the learnt forcing, shaping terms hand the end of the motion to the
            # attractor: near the goal they would fight it (a limit cycle next to an obstacle).
            return np.zeros(3), np.zeros(3)
        lin, ang = sum_couplings(self.terms, state, target)
        lin, ang = lin * gate, ang * gate
        n_lin = float(np.sqrt(lin @ lin))
        n_ang = float(np.sqrt(ang @ ang))
        if n_lin > self.max_linear:
            lin = lin * (self.max_linear / n_lin)
        if n_ang > self.max_angular:
            ang = ang * (self.max_angular / n_ang)
        return lin, ang

    def pack(self, packer: Packer, weight: float) -> None:
        """A GROUP row, each term's rows, and a SATURATE row ``[w, max_lin, max_ang, fade]``."""
        packer.add(Kind.GROUP, [weight])
        for w in self.terms:
            packer.term(w.term, w.weight)
        packer.add(Kind.SATURATE, [weight, self.max_linear, self.max_angular, self.fade_phase])


@kernel
def fade_gate(phase: float, fade_phase: float) -> float:
    """``(phase / fade_phase)^2`` below ``fade_phase``, 1 above, 0 once it falls below 0.05."""
    if fade_phase <= 0.0 or phase >= fade_phase:
        return 1.0
    gate = (phase / fade_phase) ** 2
    return gate if gate >= _GATE_OFF else 0.0


@kernel
def saturate_kernel(acc: Array, phase: float, data: Array, o: int) -> None:
    """:meth:`Saturated.acceleration` applied in place to a group's sum ``acc`` (6)."""
    gate = fade_gate(phase, data[o + 3])
    lin = 0.0
    ang = 0.0
    for i in range(3):
        acc[i] *= gate
        acc[3 + i] *= gate
        lin += acc[i] * acc[i]
        ang += acc[3 + i] * acc[3 + i]
    lin = np.sqrt(lin)
    ang = np.sqrt(ang)
    if lin > data[o + 1]:
        k = data[o + 1] / lin
        for i in range(3):
            acc[i] *= k
    if ang > data[o + 2]:
        k = data[o + 2] / ang
        for i in range(3):
            acc[3 + i] *= k
