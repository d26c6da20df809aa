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
world twists ``G^T y_o' + R_o y_C'``, which is what a Cartesian controller tracks.

A composition is packed once per move into a program (:mod:`skills.interpreter`), and each
step is one compiled call. :func:`reference_step` computes the same step with every term's
numpy reference: the tests hold the two within 1e-9.
"""

from __future__ import annotations

import operator
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from skills import quaternion as quat
from skills.couplings.forcing import LearntForcing
from skills.couplings.term import CouplingTerm, Weighted, sum_couplings
from skills.dmp import DMPParams
from skills.interpreter import Program
from skills.layout import COMMANDS, PHASES, ROW_SIZE
from skills.pose_model import PoseModel
from skills.state import STATE_SIZE, PoseState, PoseTarget, state_from, state_values
from skills.transformation import attractor, integrate
from skills.types import Array
from skills.vocabulary import ARMS, Arm


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

    @staticmethod
    def from_values(values: Array) -> DualArmState:
        """The state whose arrays are views of ``values`` (3 x 19 floats, then 3 phases)."""
        phases = values[PHASES : PHASES + 3].tolist()
        return DualArmState(
            state_from(values, phases[0], 0),
            state_from(values, phases[1], STATE_SIZE),
            state_from(values, phases[2], 2 * STATE_SIZE),
        )

    def values(self) -> Array:
        """The three states' arrays end to end, then their phases, shape (60,)."""
        o, left, right = self.object, self.left, self.right
        return np.concatenate((*o[:6], *left[:6], *right[:6], (o.phase, left.phase, right.phase)))

    def relative(self, arm: Arm) -> PoseState:
        """The palm's state in {O}."""
        return self.left if arm is Arm.LEFT else self.right


class PalmCommands(NamedTuple):
    """What the controller should track this step.

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


def _commands(row: Array) -> PalmCommands:
    """The commands in one step's output row (views)."""
    c = COMMANDS
    return PalmCommands(
        row[c : c + 6].reshape(2, 3),
        row[c + 6 : c + 14].reshape(2, 4),
        row[c + 14 : c + 26].reshape(2, 6),
        row[c + 26 : c + 32],
    )


@dataclass(frozen=True)
class Rollout:
    """An open-loop rollout of a composition: the state and commands after each step.

    Attributes
    ----------
    values : ndarray, shape (N, 92)
        One row per step, as :mod:`skills.layout`.
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
        return DualArmState.from_values(self.values[i])

    def commands(self, i: int) -> PalmCommands:
        """The commands of step ``i``."""
        return _commands(self.values[i])


@dataclass
class DualArmComposer:
    """Runs one composition of absolute and relative skills for one move.

    Build with :meth:`start`; call :meth:`step` every control tick, with the measured state
    when the loop is closed. The terms are fixed for the move; assigning a field other than
    ``state`` makes the next step pack them again.
    """

    base: PoseModel
    target: PoseTarget
    state: DualArmState
    absolute: tuple[Weighted, ...] = ()
    relative: dict[Arm, tuple[Weighted, ...]] = field(default_factory=dict)
    relative_targets: dict[Arm, PoseTarget] = field(default_factory=dict)
    _program: tuple[tuple[object, ...], Program] | None = field(
        default=None, init=False, repr=False, compare=False
    )
    #: The last step's output row and the state cut from it: read back without copying.
    _last: tuple[DualArmState, Array] | None = field(
        default=None, init=False, repr=False, compare=False
    )

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
        """
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
        )

    def object_acceleration(self, state: PoseState | None = None) -> tuple[Array, Array]:
        """Composed object acceleration (linear, angular) at ``state`` (default: current),
        from the terms' numpy references."""
        return _object_acceleration(self, state or self.state.object)

    def _values(self, state: DualArmState) -> Array:
        last = self._last
        return last[1] if last is not None and last[0] is state else state.values()

    def step(self, dt: float, measured: DualArmState | None = None) -> PalmCommands:
        """Advance every space by ``dt`` and return the palms' commands (closed loop).

        Parameters
        ----------
        dt : float
            Control period, s.
        measured : DualArmState, optional
            Close the loop on a measured state (e.g. the object's pose from the simulator).
        """
        x = self._values(measured or self.state)
        out = self.program().step(x, dt, closed_loop=True)
        self.state = DualArmState.from_values(out)
        self._last = (self.state, out)
        return _commands(out)

    def rollout(self, steps: int, dt: float) -> Rollout:
        """Predict ``steps`` steps open loop from the current state (which ends at the last).

        What moves in the world (the arms' link points of a field) is carried with the object
        from where it is now. One compiled call when no term needs Python each step.

        Raises
        ------
        ValueError
            If ``steps`` is not an integer >= 0.
        """
        if isinstance(steps, bool) or not isinstance(steps, int | np.integer) or steps < 0:
            raise ValueError(f"steps: expected an integer >= 0, got {steps!r}")
        values = self.program().rollout(self._values(self.state), dt, int(steps))
        if steps:
            self.state = DualArmState.from_values(values[-1])
            self._last = (self.state, values[-1])
        return Rollout(values)

    def commands(self) -> PalmCommands:
        """Palm poses and twists for the current state."""
        return commands_for(self.state)

    def program(self) -> Program:
        """The packed program of the current terms (packed again when a field was assigned)."""
        config = (
            self.base,
            self.target,
            self.absolute,
            self.relative,
            self.relative_targets,
        )
        packed = self._program
        if packed is None or not all(map(operator.is_, packed[0], config)):
            program = Program.of(
                self.base,
                self.target,
                self.absolute,
                [self.relative.get(arm, ()) for arm in ARMS],
                [self.relative_targets[arm] for arm in ARMS],
                self._values(self.state),
            )
            packed = self._program = (config, program)
        return packed[1]


def _object_acceleration(composer: DualArmComposer, state: PoseState) -> tuple[Array, Array]:
    params = composer.base.params
    lin, ang = attractor(state, params.alpha, params.beta, composer.target)
    terms: list[CouplingTerm] = list(composer.absolute)
    if np.any(composer.target.effective_weights[:, :6]):
        terms.insert(0, LearntForcing(composer.base))
    c_lin, c_ang = sum_couplings(terms, state, composer.target)
    return lin + c_lin, ang + c_ang


def reference_step(
    composer: DualArmComposer, dt: float, measured: DualArmState | None = None
) -> tuple[DualArmState, PalmCommands]:
    """:meth:`DualArmComposer.step` from every term's numpy reference (the composer is left
    as it is): the next state and the commands. Fields read their attached points only."""
    current = measured or composer.state
    tau, alpha_s = composer.target.tau, composer.base.params.alpha_s
    lin, ang = _object_acceleration(composer, current.object)
    obj = integrate(current.object, lin, ang, dt, tau, alpha_s)
    palms = []
    for arm in ARMS:
        s = current.relative(arm)
        lin, ang = sum_couplings(composer.relative.get(arm, ()), s, composer.relative_targets[arm])
        palms.append(integrate(s, lin, ang, dt, composer.relative_targets[arm].tau, alpha_s))
    state = DualArmState(obj, palms[0], palms[1])
    return state, commands_for(state)


def commands_for(state: DualArmState) -> PalmCommands:
    """Palm world poses and eq. (5) twists for a dual-arm state (numpy).

    ``p = y + R r``, ``q = q_o q_r`` and the twist ``[v + omega x R r + R v_r;
    omega + R omega_r]``: the grasp map's rigid-body twist ``G^T y_o'`` plus each palm's own
    motion in {O}.
    """
    o = state.object
    to_world = quat.to_matrix(o.orientation)
    positions, orientations, twists = [], [], []
    for arm in ARMS:
        r = state.relative(arm)
        lever = to_world @ r.position
        positions.append(o.position + lever)
        orientations.append(quat.multiply(o.orientation, r.orientation))
        twists.append(
            np.concatenate(
                (
                    o.velocity + np.cross(o.angular_velocity, lever) + to_world @ r.velocity,
                    o.angular_velocity + to_world @ r.angular_velocity,
                )
            )
        )
    return PalmCommands(
        np.array(positions),
        np.array(orientations),
        np.array(twists),
        np.concatenate((o.velocity, o.angular_velocity)),
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


__all__ = [
    "ROW_SIZE",
    "DualArmComposer",
    "DualArmState",
    "PalmCommands",
    "Rollout",
    "commands_for",
    "grasped_state",
    "reference_step",
    "relative_from_world",
    "state_values",
]
