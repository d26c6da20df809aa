"""Simultaneous composition of absolute and relative skills into both palms' commands.

Absolute space: one transformation system (eq. 1-4 with zero forcing) pulls the object pose
towards the move's goal over ``tau``; every selected absolute skill adds its coupling term
with its weight ``w_j`` (the learnt pick-and-place and rotation forcing terms, obstacle
steering, link-level potential-field avoidance, ...). Integrated over a step, skill ``j``
contributes the velocity ``w_j * dt * c_j``, so the object twist is the weighted sum of the
skills' velocities of the paper's eq. (5) on top of the shared attractor.

Relative space: each palm's pose in {O} moves under its relative skills alone (grasp
maintenance tracks the grasp geometry; a force-tracking variant regulates the squeeze).

Output: the palms' world poses (object pose composed with the palms' relative poses) and
world twists ``G^T y_o' + R_o y_C'`` (:func:`skills.dual_arm.compose_twists`), which is what
a Cartesian controller tracks.

A step runs every control tick on 3-vectors and quaternions, where numpy's per-call cost
exceeds the arithmetic: it reads each state once as floats, evaluates the terms as floats
(:class:`skills.coupling.ScalarCouplingTerm`), the learnt forcing terms on one basis
instance so that one evaluation of the basis serves them all, and allocates one array for
the new states and one for the commands. It gives the numbers of
:func:`skills.pose_dmp.pose_step`, :func:`skills.pose_dmp.coupled_step` and
:func:`commands_for`: the same operations in the same order. The new state's arrays are
views cut out of that array on first use (:meth:`DualArmState.cut_from`).

Started with ``compiled=True`` the step runs compiled instead (:mod:`skills.compiled`,
numba), within 1e-9 of these numbers. :meth:`DualArmComposer.rollout` steps open loop into
one array, in one compiled call when every term has a kernel.
"""

from __future__ import annotations

import operator
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from skills import quaternion as quat
from skills.basis import RBFBasis, phase_step
from skills.coupling import CouplingTerm, WeightedScalar, add_scalar_terms, scalar_evaluation
from skills.dmp import DMPParams
from skills.dual_arm import ARMS
from skills.labels import Arm
from skills.pose_dmp import (
    STATE_SIZE,
    LearntForcing,
    PoseFloats,
    PoseModel,
    PoseState,
    PoseTarget,
    StateValues,
    Weighted,
    attractor_floats,
    integrate_floats,
    pose_acceleration,
    state_from,
    state_values,
    transformation_floats,
)
from skills.types import Array

if TYPE_CHECKING:
    from skills.compiled import CompiledStep


#: The layout of one step's output (:class:`Rollout`): three states' values, their phases,
#: then the commands (palm positions 2 x 3, orientations 2 x 4, twists 2 x 6, object twist).
PHASES = 3 * STATE_SIZE
COMMANDS = PHASES + 3
ROW_SIZE = COMMANDS + 32


@dataclass(frozen=True)
class DualArmState:
    """Full state of the closed chain: the object in the world and each palm in {O}.

    Attributes
    ----------
    object : PoseState
        ``object2world`` pose, twist and accelerations; its phase is the task phase.
    left, right : PoseState
        ``palm2object`` pose and motion of each palm, expressed in {O}.
    """

    object: PoseState
    left: PoseState
    right: PoseState
    #: The buffer the composer cut this state out of, when it did (its three states' values
    #: then their phases): read back whole by the compiled step. Not copied by ``replace``.
    _values: Array | None = field(default=None, init=False, repr=False, compare=False)

    @staticmethod
    def cut_from(values: Array) -> DualArmState:
        """The state whose arrays are views of ``values`` (3 x 19 floats, then 3 phases).

        The views are made on first use: a closed control loop steps from measured states
        and reads only the commands, and eighteen views cost more than a compiled step.
        """
        state = object.__new__(DualArmState)
        object.__setattr__(state, "_values", values)
        return state

    if not TYPE_CHECKING:  # typed as the dataclass's fields; only reached before first use

        def __getattr__(self, name: str) -> PoseState:
            values = self.__dict__.get("_values")
            if values is None or name not in ("object", "left", "right"):
                raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")
            phases = values[PHASES : PHASES + 3].tolist()
            for at, (key, phase) in enumerate(
                zip(("object", "left", "right"), phases, strict=True)
            ):
                object.__setattr__(self, key, state_from(values, phase, at * STATE_SIZE))
            return self.__dict__[name]

    def relative(self, arm: Arm) -> PoseState:
        """The palm's state in {O}."""
        return self.left if arm is Arm.LEFT else self.right


class PalmCommands(NamedTuple):
    """What the controller should track this step.

    Immutable (a named tuple, as :class:`skills.pose_dmp.PoseState`: it is created every
    control step, and cheaply).

    Attributes
    ----------
    positions : ndarray, shape (2, 3)
        ``palm2world`` positions, left then right, m.
    orientations : ndarray, shape (2, 4)
        ``palm2world`` orientations.
    twists : ndarray, shape (2, 6)
        Palm twists (linear m/s, angular rad/s), world frame.
    object_twist : ndarray, shape (6,)
        The composed absolute twist of the object centre.
    """

    positions: Array
    orientations: Array
    twists: Array
    object_twist: Array


@dataclass(frozen=True)
class Rollout:
    """An open-loop rollout of a composition: the state and commands after each step.

    Attributes
    ----------
    values : ndarray, shape (N, 92)
        One row per step: the object's, the left and the right palm's
        :data:`skills.pose_dmp.StateValues` (19 floats each), their phases, then the
        commands (palm positions 2 x 3, orientations 2 x 4, twists 2 x 6, object twist 6).
    """

    values: Array

    def __len__(self) -> int:
        return int(self.values.shape[0])

    @property
    def object_positions(self) -> Array:
        """``object2world`` positions, (N, 3), m."""
        return self.values[:, 0:3]

    @property
    def object_orientations(self) -> Array:
        """``object2world`` orientations, (N, 4)."""
        return self.values[:, 9:13]

    @property
    def palm_positions(self) -> Array:
        """``palm2world`` positions, left then right, (N, 2, 3), m."""
        return self.values[:, COMMANDS : COMMANDS + 6].reshape(-1, 2, 3)

    @property
    def palm_orientations(self) -> Array:
        """``palm2world`` orientations, (N, 2, 4)."""
        return self.values[:, COMMANDS + 6 : COMMANDS + 14].reshape(-1, 2, 4)

    @property
    def palm_twists(self) -> Array:
        """Palm twists (linear, angular), world frame, (N, 2, 6)."""
        return self.values[:, COMMANDS + 14 : COMMANDS + 26].reshape(-1, 2, 6)

    def state(self, i: int) -> DualArmState:
        """The full state after step ``i``."""
        row = self.values[i]
        return DualArmState.cut_from(row)

    def commands(self, i: int) -> PalmCommands:
        """The commands of step ``i``."""
        return _commands(self.values[i])


@dataclass
class DualArmComposer:
    """Runs one composition of absolute and relative skills for one move.

    Build with :meth:`start`; call :meth:`step` every control tick, with the measured state
    when the loop is closed. The terms are fixed for the move (tuples, in mappings not to be
    changed in place); assigning a field other than ``state`` makes the next step resolve
    them again.
    """

    base: PoseModel
    target: PoseTarget
    state: DualArmState
    absolute: tuple[Weighted, ...] = ()
    relative: dict[Arm, tuple[Weighted, ...]] = field(default_factory=dict)
    relative_targets: dict[Arm, PoseTarget] = field(default_factory=dict)
    compiled: bool = False
    _plan: _Plan | None = field(default=None, init=False, repr=False, compare=False)

    @staticmethod
    def start(
        state: DualArmState,
        goal_position: ArrayLike,
        goal_orientation: ArrayLike,
        tau: float,
        absolute: Sequence[tuple[CouplingTerm, float]] = (),
        relative: Mapping[Arm, Sequence[tuple[CouplingTerm, float]]] | None = None,
        params: DMPParams | None = None,
        fresh_phase: bool = True,
        compiled: bool = False,
    ) -> DualArmComposer:
        """Compose skills from a handed-over full state towards a goal pose of the object.

        Parameters
        ----------
        state : DualArmState
            The previous skill's last full state (the handover).
        goal_position, goal_orientation : array_like, shapes (3,), (4,)
            Where the object should end, world frame.
        tau : float
            Temporal scaling of the move, s.
        absolute : sequence of (CouplingTerm, weight)
            Absolute skills' coupling terms and their weights ``w_j``.
        relative : mapping Arm -> sequence of (CouplingTerm, weight)
            Relative skills per palm and their weights ``w_k``.
        params : DMPParams, optional
            Gains of the shared transformation system.
        fresh_phase : bool
            Restart the phase at 1 (a new move) rather than continue the handed-over one.
        compiled : bool
            Run each step compiled (:mod:`skills.compiled`, needs numba): the same numbers
            within 1e-9, several times faster.

        Raises
        ------
        RuntimeError
            If ``compiled`` is asked for and numba is not installed.
        """
        if compiled:
            from skills.compiled import require

            require()
        base = PoseModel.still(params)
        obj = state.object.with_phase(1.0) if fresh_phase else state.object
        target = base.target(obj.position, obj.orientation, goal_position, goal_orientation, tau)
        rel_targets = {
            arm: PoseModel.still(params).target(
                state.relative(arm).position,
                state.relative(arm).orientation,
                state.relative(arm).position,
                state.relative(arm).orientation,
                tau,
            )
            for arm in ARMS
        }
        return DualArmComposer(
            base,
            target,
            replace(state, object=obj),
            tuple(Weighted(c, float(w)) for c, w in absolute),
            {
                arm: tuple(Weighted(c, float(w)) for c, w in (relative or {}).get(arm, ()))
                for arm in ARMS
            },
            rel_targets,
            compiled,
        )

    def object_acceleration(self, state: PoseState | None = None) -> tuple[Array, Array]:
        """Composed object acceleration (linear, angular) at ``state`` (default: current)."""
        return pose_acceleration(state or self.state.object, self.base, self.target, self.absolute)

    def step(self, dt: float, measured: DualArmState | None = None) -> PalmCommands:
        """Advance every space by ``dt`` and return the palms' commands.

        Parameters
        ----------
        dt : float
            Control period, s.
        measured : DualArmState, optional
            Close the loop on a measured state (e.g. the object's pose from the simulator).
        """
        current = measured or self.state
        plan = self._resolved()
        if plan.compiled is not None:
            values = current._values  # a state the composer cut: its fields may not be yet
            states = None if values is not None else (current.object, current.left, current.right)
            out = plan.compiled(states, dt, values)
            self.state = DualArmState.cut_from(out)
            return _commands(out)
        obj, obj_phase = plan.obj(current.object, dt)
        left, left_phase = plan.left(current.left, dt)
        right, right_phase = plan.right(current.right, dt)
        # One allocation; the states are views into it.
        values = np.array((*obj, *left, *right, obj_phase, left_phase, right_phase))
        self.state = DualArmState.cut_from(values)
        return palm_commands(obj, left, right)

    def rollout(self, steps: int, dt: float) -> Rollout:
        """Step ``steps`` times open loop from the current state (which ends at the last).

        Compiled, and with every term compiled, the whole rollout is one call into compiled
        code; otherwise it is :meth:`step` ``steps`` times.

        Raises
        ------
        ValueError
            If ``steps`` is not an integer >= 0.
        """
        if isinstance(steps, bool) or not isinstance(steps, int | np.integer) or steps < 0:
            raise ValueError(f"steps: expected an integer >= 0, got {steps!r}")
        plan = self._resolved()
        if plan.compiled is not None:
            s = self.state
            states = None if s._values is not None else (s.object, s.left, s.right)
            values = plan.compiled.rollout(states, dt, int(steps), s._values)
            if steps:
                self.state = DualArmState.cut_from(values[-1])
            return Rollout(values)
        values = np.empty((int(steps), ROW_SIZE))
        for row in values:
            cmd = self.step(dt)
            row[:COMMANDS] = self.state._values
            row[COMMANDS:] = np.concatenate(
                (
                    cmd.positions.ravel(),
                    cmd.orientations.ravel(),
                    cmd.twists.ravel(),
                    cmd.object_twist,
                )
            )
        return Rollout(values)

    def commands(self) -> PalmCommands:
        """Palm poses and twists for the current state."""
        return commands_for(self.state)

    def _resolved(self) -> _Plan:
        """The plan for the current terms: resolved again only when a field was reassigned."""
        plan = self._plan
        config = (
            self.base,
            self.target,
            self.absolute,
            self.relative,
            self.relative_targets,
            self.compiled,
        )
        if plan is None or not all(map(operator.is_, plan.configuration, config)):
            plan = self._plan = _Plan.of(self, config)
        return plan


def _commands(row: Array) -> PalmCommands:
    """The commands in one step's output row (views)."""
    c = COMMANDS
    return PalmCommands(
        row[c : c + 6].reshape(2, 3),
        row[c + 6 : c + 14].reshape(2, 4),
        row[c + 14 : c + 26].reshape(2, 6),
        row[c + 26 : c + 32],
    )


def _scalar_terms(terms: Sequence[Weighted]) -> tuple[WeightedScalar, ...]:
    return tuple((scalar_evaluation(w.term), w.weight) for w in terms)


@dataclass(frozen=True, eq=False)
class _ObjectStep:
    """:func:`skills.pose_dmp.pose_step` of the object in floats, its terms resolved.

    The base model's own forcing is skipped when it is zero (the composer's still base): it
    would add exact zeros.
    """

    base: PoseModel
    forced: bool
    target: PoseTarget
    terms: tuple[WeightedScalar, ...]

    @staticmethod
    def of(base: PoseModel, target: PoseTarget, absolute: Sequence[Weighted]) -> _ObjectStep:
        forced = bool(np.any(target.effective_weights[:, :6]))
        basis = base.position.forcing.basis
        return _ObjectStep(base, forced, target, _scalar_terms(_on_basis(absolute, basis)))

    def __call__(self, state: PoseState, dt: float) -> tuple[StateValues, float]:
        """The next state's values and phase."""
        pose = PoseFloats.of(state)
        if self.forced:
            acc = transformation_floats(pose, self.base, self.target)
        else:
            acc = attractor_floats(pose, self.base.params, self.target)
        add_scalar_terms(acc, self.terms, pose, self.target)
        phase = phase_step(pose.phase, dt, self.target.tau, self.base.params.alpha_s)
        return integrate_floats(pose, acc, dt), phase


def _on_basis(terms: Sequence[Weighted], basis: RBFBasis) -> list[Weighted]:
    # Learnt forcing terms with the same basis functions read them from one instance, whose
    # activations at a phase are computed once (the same values: the same numbers).
    return [
        Weighted(LearntForcing(w.term.model, basis), w.weight)
        if isinstance(w.term, LearntForcing) and w.term.basis.same_as(basis)
        else w
        for w in terms
    ]


@dataclass(frozen=True, eq=False)
class _PalmStep:
    """:func:`skills.pose_dmp.coupled_step` of a palm in {O} in floats, its terms resolved."""

    target: PoseTarget
    terms: tuple[WeightedScalar, ...]
    alpha_s: float

    def __call__(self, state: PoseState, dt: float) -> tuple[StateValues, float]:
        """The next state's values and phase."""
        pose = PoseFloats.of(state)
        acc = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
        add_scalar_terms(acc, self.terms, pose, self.target)
        phase = phase_step(pose.phase, dt, self.target.tau, self.alpha_s)
        return integrate_floats(pose, acc, dt), phase


@dataclass(frozen=True, eq=False)
class _Plan:
    """What a composition evaluates every tick, resolved from its terms once per move.

    ``configuration`` is what it was resolved from (compared by identity each step).
    """

    configuration: tuple[object, ...]
    obj: _ObjectStep
    left: _PalmStep
    right: _PalmStep
    compiled: CompiledStep | None = None

    @staticmethod
    def of(composer: DualArmComposer, configuration: tuple[object, ...]) -> _Plan:
        compiled = None
        if composer.compiled:
            from skills.compiled import CompiledStep

            compiled = CompiledStep.of(
                composer.base,
                composer.target,
                composer.absolute,
                composer.relative,
                composer.relative_targets,
            )
        alpha_s = composer.base.params.alpha_s
        palms = [
            _PalmStep(
                composer.relative_targets[arm],
                _scalar_terms(composer.relative.get(arm, ())),
                alpha_s,
            )
            for arm in ARMS
        ]
        return _Plan(
            configuration,
            _ObjectStep.of(composer.base, composer.target, composer.absolute),
            palms[0],
            palms[1],
            compiled,
        )


def commands_for(state: DualArmState) -> PalmCommands:
    """Palm world poses and eq. (5) twists for a dual-arm state."""
    return palm_commands(
        state_values(state.object), state_values(state.left), state_values(state.right)
    )


def palm_commands(obj: StateValues, left: StateValues, right: StateValues) -> PalmCommands:
    """Palm world poses and eq. (5) twists from the object's and palms' state values.

    The same algebra as :func:`skills.dual_arm.palm_poses` and
    :func:`skills.dual_arm.compose_twists` (one absolute and one relative twist), in floats:
    it runs every control tick, on 3-vectors, where numpy's per-call cost dominates.
    """
    px, py, pz, vx, vy, vz = obj[0:6]
    x, y, z, w, wx, wy, wz = obj[9:16]
    q = (x, y, z, w)
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = quat.matrix_floats(q)
    positions: list[float] = []
    orientations: list[float] = []
    twists: list[float] = []
    for palm in (left, right):
        a0, a1, a2, b0, b1, b2 = palm[0:6]
        qx, qy, qz, qw, c0, c1, c2 = palm[9:16]
        l0 = r00 * a0 + r01 * a1 + r02 * a2  # lever arm: object centre to palm, world frame
        l1 = r10 * a0 + r11 * a1 + r12 * a2
        l2 = r20 * a0 + r21 * a1 + r22 * a2
        positions += (px + l0, py + l1, pz + l2)
        orientations += quat.multiply_scalar(q, (qx, qy, qz, qw))
        twists += (
            vx + wy * l2 - wz * l1 + r00 * b0 + r01 * b1 + r02 * b2,  # G^T y_o' + R y_C'
            vy + wz * l0 - wx * l2 + r10 * b0 + r11 * b1 + r12 * b2,
            vz + wx * l1 - wy * l0 + r20 * b0 + r21 * b1 + r22 * b2,
            wx + r00 * c0 + r01 * c1 + r02 * c2,
            wy + r10 * c0 + r11 * c1 + r12 * c2,
            wz + r20 * c0 + r21 * c1 + r22 * c2,
        )
    # One allocation for all four arrays; each is a view into it.
    out = np.array((*positions, *orientations, *twists, vx, vy, vz, wx, wy, wz))
    return PalmCommands(
        out[0:6].reshape(2, 3), out[6:14].reshape(2, 4), out[14:26].reshape(2, 6), out[26:32]
    )


def grasped_state(
    object_position: ArrayLike,
    object_orientation: ArrayLike,
    left_in_object: tuple[ArrayLike, ArrayLike],
    right_in_object: tuple[ArrayLike, ArrayLike],
) -> DualArmState:
    """A dual-arm state at rest: the object's pose and each palm's pose in {O}."""
    return DualArmState(
        PoseState.at_rest(object_position, object_orientation),
        PoseState.at_rest(*left_in_object),
        PoseState.at_rest(*right_in_object),
    )


def relative_from_world(
    object_position: Array,
    object_orientation: Array,
    palm_position: Array,
    palm_orientation: Array,
) -> tuple[Array, Array]:
    """``palm2object`` from ``object2world`` and ``palm2world``."""
    inv = quat.conjugate(object_orientation)
    return (
        quat.rotate(inv, palm_position - object_position),
        quat.multiply(inv, palm_orientation),
    )
