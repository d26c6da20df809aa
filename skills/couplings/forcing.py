"""The learnt RBF forcing term of a pose DMP, as a coupling term on a shared transformation system.

``f(s) / tau^2 = s (psi(s) @ W) / (sum(psi(s)) tau^2)``, with ``W`` the model's weights with
the running target's scalings folded in (:attr:`skills.state.PoseTarget.effective_weights`)
and ``psi`` the Gaussian basis activations at the phase ``s``.
"""

from __future__ import annotations

import math

import numpy as np

from skills.kernel import kernel
from skills.pose_model import PoseModel
from skills.program import Kind, Packer
from skills.state import PoseState, PoseTarget
from skills.types import Array


def forcing_acceleration(s: float, table: Array, target: PoseTarget) -> tuple[Array, Array]:
    """``f(s) / tau^2``, linear (3,) and angular (3,), from a basis exponent table (3, K)
    and a target binding the forcing's weights (``target.effective_weights``, (K, 7))."""
    raw = np.exp(np.array((s * s, s, 1.0)) @ table) @ target.effective_weights
    f = raw[:6] * (s / (max(raw[6], 1e-300) * target.tau * target.tau))
    return f[:3], f[3:]


class LearntForcing:
    """The learnt RBF forcing term of ``model`` as a :class:`skills.couplings.term.CouplingTerm`.

    Used to compose a learnt skill with others on a shared transformation system: its forcing
    is scaled for the running target's start and goal with ``model``'s own scaling, and read
    at the running phase.

    Parameters
    ----------
    model : PoseModel
    """

    def __init__(self, model: PoseModel) -> None:
        self.model = model
        self._for: PoseTarget | None = None
        self._own: PoseTarget | None = None

    def own_target(self, target: PoseTarget) -> PoseTarget:
        """The model's target for the running target's start, goal and ``tau`` (cached)."""
        if self._for is not target:
            self._own = self.model.target(
                target.start_position,
                target.start_orientation,
                target.goal_position,
                target.goal_orientation,
                target.tau,
            )
            self._for = target
        assert self._own is not None
        return self._own

    def acceleration(self, state: PoseState, target: PoseTarget) -> tuple[Array, Array]:
        """(linear m/s^2, angular rad/s^2) at ``state.phase``."""
        table = self.model.position.forcing.basis.exponent_table
        return forcing_acceleration(state.phase, table, self.own_target(target))

    def pack(self, packer: Packer, weight: float) -> None:
        """A FORCING block: ``[w, K, tau, table offset, W (K, 7)]``."""
        own = self.own_target(packer.target)
        table = self.model.position.forcing.basis.exponent_table
        at = packer.table(table)
        block = [weight, float(table.shape[1]), own.tau, float(at)]
        packer.add(Kind.FORCING, block + own.effective_weights.ravel().tolist())


@kernel
def activations_kernel(s: float, data: Array, table: int, size: int, psi: Array) -> None:
    """Unnormalised basis activations at phase ``s`` into ``psi[:size]``, from the exponent
    table (3, K) at ``data[table:]`` (:attr:`skills.basis.RBFBasis.exponent_table`)."""
    s2 = s * s
    for i in range(size):
        psi[i] = math.exp(
            s2 * data[table + i] + s * data[table + size + i] + data[table + 2 * size + i]
        )


@kernel
def forcing_kernel(s: float, data: Array, o: int, psi: Array, a: Array) -> None:
    """:meth:`LearntForcing.acceleration` at phase ``s`` from its block at ``data[o:]``, with
    ``psi`` its basis activations at ``s``."""
    size = int(data[o + 1])
    tau = data[o + 2]
    weights = o + 4
    r0 = r1 = r2 = r3 = r4 = r5 = r6 = 0.0
    for i in range(size):
        row = weights + 7 * i
        p = psi[i]
        r0 += p * data[row]
        r1 += p * data[row + 1]
        r2 += p * data[row + 2]
        r3 += p * data[row + 3]
        r4 += p * data[row + 4]
        r5 += p * data[row + 5]
        r6 += p * data[row + 6]
    k = s / (max(r6, 1e-300) * tau * tau)
    a[0], a[1], a[2], a[3], a[4], a[5] = r0 * k, r1 * k, r2 * k, r3 * k, r4 * k, r5 * k
