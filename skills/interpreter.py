"""The composition step's interpreter: one compiled call runs a move's packed terms.

A composition packs itself once per move into a :class:`Program` (each term by its own
``pack``, :mod:`skills.program`): per space, the transformation system's row; per term, a row
``[space, kind, offset]`` over one block of parameters. :func:`step_kernel` then evaluates
every row with its term's kernel, sums them (groups of rows under their saturation), and
integrates the three spaces and the palms' commands, in one call; :func:`rollout_kernel`
repeats it open loop. What runs in Python, before a call: the hooks of terms whose
parameters come from Python (a distance query answered by FCL, a term without a kernel), and,
closed loop, the refreshers of what moves in the world (the arms' link points).

Layouts: the state ``x`` and a step's output as :mod:`skills.layout`; ``spaces`` (3, 13) per
space ``[attractor?, kp, kd, goal xyz, goal xyzw, tau, alpha_s, largest basis size]``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from skills.couplings.forcing import LearntForcing, activations_kernel, forcing_kernel
from skills.couplings.grasp import grasp_kernel
from skills.couplings.limits import workspace_kernel
from skills.couplings.potential import potential_kernel
from skills.couplings.saturated import saturate_kernel
from skills.couplings.steering import steering_kernel
from skills.couplings.term import Weighted
from skills.dmp import DMPParams
from skills.kernel import kernel, matrix_q, multiply_q, quaternion_at
from skills.layout import COMMANDS, PHASES, ROW_SIZE
from skills.pose_model import PoseModel
from skills.program import Hook, Kind, Packer
from skills.state import STATE_SIZE, PoseState, PoseTarget, state_values
from skills.transformation import attractor_kernel, integrate_kernel, phase_kernel
from skills.types import Array

#: How deeply groups may nest.
MAX_DEPTH = 8

FORCING, STEERING, POTENTIAL, GRASP, WORKSPACE, EXTERNAL, GROUP, SATURATE = (
    int(Kind.FORCING),
    int(Kind.STEERING),
    int(Kind.POTENTIAL),
    int(Kind.GRASP),
    int(Kind.WORKSPACE),
    int(Kind.EXTERNAL),
    int(Kind.GROUP),
    int(Kind.SATURATE),
)


def _space_row(params: DMPParams, target: PoseTarget, attractor: bool) -> list[float]:
    tau = target.tau
    return [
        1.0 if attractor else 0.0,
        params.alpha * params.beta / (tau * tau),
        params.alpha / tau,
        *target.goal_position.tolist(),
        *target.goal_orientation.tolist(),
        tau,
        params.alpha_s,  # the palms' phases decay as the object's
    ]


@dataclass(frozen=True, eq=False)
class Program:
    """One move's composition packed for the interpreter (build with :meth:`of`).

    Attributes
    ----------
    spaces : ndarray, shape (3, 13)
    rows : ndarray, shape (T, 3), int
        ``[space, kind, offset]`` per row.
    data : ndarray
        The rows' blocks; hooks and refreshers write theirs before each step.
    hooks, refreshers : tuple of Hook
    """

    spaces: Array
    rows: npt.NDArray[np.int64]
    data: Array
    hooks: tuple[Hook, ...]
    refreshers: tuple[Hook, ...]

    @staticmethod
    def of(
        base: PoseModel,
        target: PoseTarget,
        absolute: Sequence[Weighted],
        relative: Sequence[Sequence[Weighted]],
        relative_targets: Sequence[PoseTarget],
        start: Array,
    ) -> Program:
        """Pack a composition: the object's base model, target and terms, then each palm's.

        ``start`` is the state (:mod:`skills.layout`) the refreshers first write from.
        """
        params = base.params
        rows = [_space_row(params, target, True)]
        rows += [_space_row(params, t, False) for t in relative_targets]
        packer = Packer(0, target)
        if np.any(target.effective_weights[:, :6]):  # a forced base: its forcing is a term
            packer.term(LearntForcing(base), 1.0)
        for space, (terms, space_target) in enumerate(
            [(absolute, target), *zip(relative, relative_targets, strict=True)]
        ):
            packer.space, packer.target = space, space_target
            for w in terms:
                packer.term(w.term, w.weight)
        for row in rows:
            row.append(float(max(packer.basis_size, 1)))
        program = Program(
            np.array(rows),
            np.array(packer.rows, dtype=np.int64).reshape(-1, 3),
            np.array([*packer.values, 0.0]),  # never empty
            tuple(packer.hooks),
            tuple(packer.refreshers),
        )
        for refresh in program.refreshers:
            refresh(start, program.data)
        return program

    @staticmethod
    def single(
        model: PoseModel, target: PoseTarget, couplings: Sequence[object], start: Array
    ) -> Program:
        """Pack one pose DMP: ``model``'s attractor and forcing towards ``target``, and its
        coupling terms (for :meth:`pose_step`; ``start`` is its 19 values then its phase)."""
        row = _space_row(model.params, target, True)
        packer = Packer(0, target, spaces=1)
        if np.any(target.effective_weights[:, :6]):
            packer.term(LearntForcing(model), 1.0)
        for term in couplings:
            packer.term(term, 1.0)
        row.append(float(max(packer.basis_size, 1)))
        program = Program(
            np.array([row]),
            np.array(packer.rows, dtype=np.int64).reshape(-1, 3),
            np.array([*packer.values, 0.0]),
            tuple(packer.hooks),
            tuple(packer.refreshers),
        )
        for refresh in program.refreshers:
            refresh(start, program.data)
        return program

    def pose_step(self, x: Array, dt: float) -> Array:
        """The next state of a single pose DMP (:meth:`single`), closed loop, from ``x``."""
        for refresh in self.refreshers:
            refresh(x, self.data)
        for hook in self.hooks:
            hook(x, self.data)
        out = np.empty(STATE_SIZE + 1)
        pose_step_kernel(x, self.spaces, self.rows, self.data, float(dt), out)
        return out

    def step(self, x: Array, dt: float, closed_loop: bool = True) -> Array:
        """The next state and the commands (:data:`skills.layout.ROW_SIZE`) from ``x``.

        Closed loop, what moves in the world is read again first (the refreshers).
        """
        if closed_loop:
            for refresh in self.refreshers:
                refresh(x, self.data)
        for hook in self.hooks:
            hook(x, self.data)
        out = np.empty(ROW_SIZE)
        step_kernel(x, self.spaces, self.rows, self.data, float(dt), out)
        return out

    def rollout(self, x: Array, dt: float, steps: int) -> Array:
        """``steps`` steps open loop from ``x``: row ``i`` of ``(steps, ROW_SIZE)`` is step
        ``i``'s output. One compiled call when no hook runs in Python, else one per step."""
        out = np.empty((steps, ROW_SIZE))
        if steps == 0:
            return out
        if self.hooks:
            out[0] = self.step(x, dt, closed_loop=False)
            for i in range(1, steps):
                out[i] = self.step(out[i - 1], dt, closed_loop=False)
            return out
        rollout_kernel(x, self.spaces, self.rows, self.data, float(dt), out)
        return out


def kernel_acceleration(term: object, state: PoseState, target: PoseTarget) -> tuple[Array, Array]:
    """What the interpreter makes of one term at ``state``: linear (3,) and angular (3,).

    The term packed alone (with weight 1) and its rows evaluated by the compiled kernels,
    hooks included: compare it with the term's numpy ``acceleration`` to test a kernel.
    """
    packer = Packer(0, target)
    packer.term(term, 1.0)
    x = np.zeros(PHASES + 3)
    x[:STATE_SIZE] = state_values(state)
    x[PHASES] = state.phase
    data = np.array([*packer.values, 0.0])
    for hook in (*packer.refreshers, *packer.hooks):
        hook(x, data)
    spaces = np.zeros((3, 13))
    spaces[:, 10] = target.tau
    spaces[:, 12] = max(packer.basis_size, 1)
    acc = np.empty((3, 6))
    rows = np.array(packer.rows, dtype=np.int64).reshape(-1, 3)
    accelerations_kernel(x, spaces, rows, data, acc)
    return acc[0, :3].copy(), acc[0, 3:].copy()


@kernel
def commands_kernel(out: Array) -> None:
    """Palm world poses and eq. (5) twists from the new state in ``out``, into its commands:
    ``p = y + R r``, ``q = q_o q_r`` and ``[v + omega x R r + R v_r; omega + R omega_r]``
    (``G^T y_o'`` plus each palm's own motion in {O})."""
    m = matrix_q(quaternion_at(out, 9))
    q_obj = quaternion_at(out, 9)
    vx, vy, vz, wx, wy, wz = out[3], out[4], out[5], out[13], out[14], out[15]
    for arm in range(2):
        b = STATE_SIZE * (1 + arm)
        a0, a1, a2 = out[b], out[b + 1], out[b + 2]
        l0 = m[0] * a0 + m[1] * a1 + m[2] * a2  # lever arm: object centre to palm, world
        l1 = m[3] * a0 + m[4] * a1 + m[5] * a2
        l2 = m[6] * a0 + m[7] * a1 + m[8] * a2
        p = COMMANDS + 3 * arm
        out[p] = out[0] + l0
        out[p + 1] = out[1] + l1
        out[p + 2] = out[2] + l2
        q = COMMANDS + 6 + 4 * arm
        out[q], out[q + 1], out[q + 2], out[q + 3] = multiply_q(q_obj, quaternion_at(out, b + 9))
        b0, b1, b2 = out[b + 3], out[b + 4], out[b + 5]
        c0, c1, c2 = out[b + 13], out[b + 14], out[b + 15]
        t = COMMANDS + 14 + 6 * arm
        out[t] = vx + wy * l2 - wz * l1 + m[0] * b0 + m[1] * b1 + m[2] * b2
        out[t + 1] = vy + wz * l0 - wx * l2 + m[3] * b0 + m[4] * b1 + m[5] * b2
        out[t + 2] = vz + wx * l1 - wy * l0 + m[6] * b0 + m[7] * b1 + m[8] * b2
        out[t + 3] = wx + m[0] * c0 + m[1] * c1 + m[2] * c2
        out[t + 4] = wy + m[3] * c0 + m[4] * c1 + m[5] * c2
        out[t + 5] = wz + m[6] * c0 + m[7] * c1 + m[8] * c2
    t = COMMANDS + 26
    out[t], out[t + 1], out[t + 2] = vx, vy, vz
    out[t + 3], out[t + 4], out[t + 5] = wx, wy, wz


@kernel
def accelerations_kernel(
    x: Array, spaces: Array, rows: npt.NDArray[np.int64], data: Array, acc: Array
) -> None:
    """Every space's summed accelerations into ``acc`` (S, 6), for the S spaces of ``spaces``
    (S, 13) and a state ``x`` of their S x 19 values then their S phases: each space's
    attractor, if it has one, and every row (groups summed under their saturation)."""
    acc[:, :] = 0.0
    phases = STATE_SIZE * spaces.shape[0]
    for sp in range(spaces.shape[0]):
        if spaces[sp, 0] != 0.0:
            attractor_kernel(x, STATE_SIZE * sp, spaces[sp], acc[sp])
    stack = np.zeros((MAX_DEPTH + 1, 6))  # level 0 is unused: the space's own sum
    level = 0
    a = np.empty(6)
    psi = np.empty(int(spaces[0, 12]))
    psi_table, psi_phase = -1, 0.0  # terms on one basis at one phase share its activations
    for t in range(rows.shape[0]):
        sp, kind, o = rows[t, 0], rows[t, 1], rows[t, 2]
        b = STATE_SIZE * sp
        if kind == GROUP:
            level += 1
            stack[level, :] = 0.0
            continue
        if kind == FORCING:
            s = x[phases + sp]
            table = int(data[o + 3])
            if table != psi_table or s != psi_phase:
                activations_kernel(s, data, table, int(data[o + 1]), psi)
                psi_table, psi_phase = table, s
            forcing_kernel(s, data, o, psi, a)
        elif kind == STEERING:
            steering_kernel(x, b, data, o, a)
        elif kind == POTENTIAL:
            potential_kernel(x, b, data, o, a)
        elif kind == GRASP:
            grasp_kernel(x, b, data, o, a)
        elif kind == WORKSPACE:
            workspace_kernel(x, b, data, o, a)
        elif kind == EXTERNAL:
            for i in range(6):
                a[i] = data[o + 1 + i]
        else:  # SATURATE: close the innermost group
            for i in range(6):
                a[i] = stack[level, i]
            saturate_kernel(a, x[phases + sp], data, o)
            level -= 1
        w = data[o]
        if level == 0:
            for i in range(6):
                acc[sp, i] += w * a[i]
        else:
            for i in range(6):
                stack[level, i] += w * a[i]


@kernel
def step_kernel(
    x: Array, spaces: Array, rows: npt.NDArray[np.int64], data: Array, dt: float, out: Array
) -> None:
    """One composition step: every space's accelerations, integration, phases, commands."""
    acc = np.empty((3, 6))
    accelerations_kernel(x, spaces, rows, data, acc)
    for sp in range(3):
        integrate_kernel(x, STATE_SIZE * sp, acc[sp], dt, out)
        out[PHASES + sp] = phase_kernel(x[PHASES + sp], dt, spaces[sp, 10], spaces[sp, 11])
    commands_kernel(out)


@kernel
def pose_step_kernel(
    x: Array, spaces: Array, rows: npt.NDArray[np.int64], data: Array, dt: float, out: Array
) -> None:
    """One step of a single pose DMP (one space): its accelerations, integration and phase;
    ``x`` and ``out`` are its 19 values then its phase."""
    acc = np.empty((1, 6))
    accelerations_kernel(x, spaces, rows, data, acc)
    integrate_kernel(x, 0, acc[0], dt, out)
    out[STATE_SIZE] = phase_kernel(x[STATE_SIZE], dt, spaces[0, 10], spaces[0, 11])


@kernel
def rollout_kernel(
    x: Array, spaces: Array, rows: npt.NDArray[np.int64], data: Array, dt: float, out: Array
) -> None:
    """``out.shape[0]`` steps open loop from ``x``: row ``i`` of ``out`` is step ``i``'s."""
    step_kernel(x, spaces, rows, data, dt, out[0])
    for i in range(1, out.shape[0]):
        step_kernel(out[i - 1], spaces, rows, data, dt, out[i])
