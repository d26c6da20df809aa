"""Pose DMPs: three positional DMPs and one quaternion DMP sharing one phase, run alone.

:mod:`skills.pose_model` learns a :class:`PoseModel`; this module runs one: the pure
functions :func:`pose_step` and :func:`pose_rollout`, the acceleration blend at a skill switch
(:class:`HandoverBlend`) and the thin stateful :class:`PoseDMP`. The transformation system's
attractor and integration are :mod:`skills.transformation`'s; a dual-arm composition of many
skills runs compiled (:mod:`skills.composer`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike

from skills.couplings.forcing import forcing_acceleration
from skills.couplings.term import CouplingTerm, Weighted, sum_couplings
from skills.dmp import linear_rollout
from skills.interpreter import Program
from skills.pose_model import PoseModel, fit_pose
from skills.quaternion_dmp import integrate_orientation
from skills.state import STATE_SIZE, PoseState, PoseTarget, state_from, state_values
from skills.transformation import attractor, integrate
from skills.types import Array

__all__ = [
    "STATE_SIZE",
    "HandoverBlend",
    "PoseDMP",
    "PoseModel",
    "PoseState",
    "PoseTarget",
    "PoseTrajectory",
    "Weighted",
    "coupled_step",
    "fit_pose",
    "pose_acceleration",
    "pose_rollout",
    "pose_step",
    "state_from",
    "state_values",
]


def pose_acceleration(
    state: PoseState,
    model: PoseModel,
    target: PoseTarget,
    couplings: Sequence[CouplingTerm] = (),
) -> tuple[Array, Array]:
    """Linear and angular acceleration ``(3,), (3,)`` of the DMP at ``state``.

    ``(alpha (beta (g - y) - tau yd) + f) / tau^2 + c`` for position and the same with the
    short-way rotation error ``2 log(g conj(q))`` for orientation. The forcing comes from
    ``target.effective_weights`` (the target binds the model's forcing to a start and goal).
    """
    p = model.params
    lin, ang = attractor(state, p.alpha, p.beta, target)
    f_lin, f_ang = forcing_acceleration(
        state.phase, model.position.forcing.basis.exponent_table, target
    )
    c_lin, c_ang = sum_couplings(couplings, state, target)
    return lin + f_lin + c_lin, ang + f_ang + c_ang


def pose_step(
    state: PoseState,
    model: PoseModel,
    target: PoseTarget,
    dt: float,
    couplings: Sequence[CouplingTerm] = (),
) -> PoseState:
    """Advance a pose DMP by ``dt`` (closed loop: ``state`` may be the measured one).

    Semi-implicit Euler for position and angular velocity, the exponential map for the
    quaternion, the exact solution for the phase (:func:`skills.transformation.integrate`).

    Parameters
    ----------
    state : PoseState
    model : PoseModel
    target : PoseTarget
        Built by ``model.target``.
    dt : float
        Step, s.
    couplings : sequence of CouplingTerm
        Additive accelerations, summed.

    Returns
    -------
    PoseState
        The next state; its accelerations are the ones applied over this step.
    """
    lin, ang = pose_acceleration(state, model, target, couplings)
    return integrate(state, lin, ang, dt, target.tau, model.params.alpha_s)


def coupled_step(
    state: PoseState,
    target: PoseTarget,
    dt: float,
    couplings: Sequence[CouplingTerm],
    alpha_s: float,
) -> PoseState:
    """Advance a pose driven by coupling terms alone (no attractor of its own).

    Relative-space skills such as grasp maintenance carry their own reference; this integrates
    their summed accelerations with the same scheme as :func:`pose_step`.
    """
    lin, ang = sum_couplings(couplings, state, target)
    return integrate(state, lin, ang, dt, target.tau, alpha_s)


@dataclass(frozen=True)
class PoseTrajectory:
    """A sampled pose trajectory; every array has the same first length ``N``.

    Attributes
    ----------
    t : ndarray, shape (N,)
        s since the rollout started.
    positions, velocities, accelerations : ndarray, shape (N, 3)
    orientations : ndarray, shape (N, 4)
    angular_velocities, angular_accelerations : ndarray, shape (N, 3)
    phase : ndarray, shape (N,)
    """

    t: Array
    positions: Array
    velocities: Array
    accelerations: Array
    orientations: Array
    angular_velocities: Array
    angular_accelerations: Array
    phase: Array

    def __len__(self) -> int:
        return int(self.t.shape[0])

    def state(self, i: int) -> PoseState:
        """Full state at sample ``i`` (negative indices count from the end)."""
        return PoseState(
            self.positions[i].copy(),
            self.velocities[i].copy(),
            self.accelerations[i].copy(),
            self.orientations[i].copy(),
            self.angular_velocities[i].copy(),
            self.angular_accelerations[i].copy(),
            float(self.phase[i]),
        )

    def twists(self) -> Array:
        """Linear and angular velocities stacked, shape (N, 6)."""
        return np.concatenate((self.velocities, self.angular_velocities), axis=1)

    @staticmethod
    def from_states(states: Sequence[PoseState], dt: float) -> PoseTrajectory:
        """Stack a list of states sampled every ``dt`` seconds."""
        return PoseTrajectory(
            np.arange(len(states)) * dt,
            np.array([s.position for s in states]),
            np.array([s.velocity for s in states]),
            np.array([s.acceleration for s in states]),
            np.array([s.orientation for s in states]),
            np.array([s.angular_velocity for s in states]),
            np.array([s.angular_acceleration for s in states]),
            np.array([s.phase for s in states]),
        )


def pose_rollout(
    model: PoseModel,
    target: PoseTarget,
    start: PoseState,
    dt: float,
    n_steps: int | None = None,
    couplings: Sequence[CouplingTerm] = (),
) -> PoseTrajectory:
    """Open-loop rollout of ``n_steps`` steps (``n_steps + 1`` samples, start included).

    Without couplings, positions are integrated for all steps at once
    (:func:`skills.dmp.linear_rollout`) and orientations in a scalar loop; with couplings,
    which may depend on the state, it steps :func:`pose_step`. Both give the same numbers
    as stepping.

    Parameters
    ----------
    model : PoseModel
    target : PoseTarget
    start : PoseState
        Initial full state; its phase may be mid-motion.
    dt : float
        Step, s.
    n_steps : int, optional
        Defaults to ``1.5 * tau / dt``.
    couplings : sequence of CouplingTerm
    """
    if not (np.isfinite(dt) and dt > 0):
        raise ValueError(f"dt: expected a positive step in s, got {dt!r}")
    p = model.params
    tau = target.tau
    n = int(n_steps if n_steps is not None else np.ceil(1.5 * tau / dt))
    if n < 1:
        raise ValueError(f"n_steps: expected at least 1, got {n}")
    if couplings:
        states = [start]
        st = start
        for _ in range(n):
            st = pose_step(st, model, target, dt, couplings)
            states.append(st)
        traj = PoseTrajectory.from_states(states, dt)
        return _with_final_acceleration(traj, model, target, couplings)
    k = np.arange(n + 1)
    s = start.phase * np.exp(-p.alpha_s * k * dt / tau)
    phi = model.position.forcing.basis.normalised(s) * s[:, None]
    f_lin = (phi @ model.position.forcing.weights) @ target.position_matrix.T
    f_ang = (phi @ model.orientation.forcing.weights) @ target.orientation_matrix.T
    y, yd, ydd = linear_rollout(
        start.position,
        start.velocity,
        target.goal_position,
        f_lin[:-1] / (tau * tau),
        p.alpha,
        p.beta,
        tau,
        dt,
    )
    q, w, wd = integrate_orientation(
        start.orientation,
        start.angular_velocity,
        target.goal_orientation,
        f_ang[:-1],
        None,
        p.alpha,
        p.beta,
        tau,
        dt,
    )
    traj = PoseTrajectory(
        k * dt, y, yd, np.vstack((ydd, ydd[-1:])), q, w, np.vstack((wd, wd[-1:])), s
    )
    return _with_final_acceleration(traj, model, target, couplings)


def _with_final_acceleration(
    traj: PoseTrajectory,
    model: PoseModel,
    target: PoseTarget,
    couplings: Sequence[CouplingTerm],
) -> PoseTrajectory:
    """Replace the last sample's accelerations by the ones the DMP has at that state."""
    acc, ang = pose_acceleration(traj.state(-1), model, target, couplings)
    traj.accelerations[-1] = acc
    traj.angular_accelerations[-1] = ang
    return traj


#: Below this phase (about 150 tau into a skill) a :class:`HandoverBlend` is not added: its
#: decay ``(s / s0)^rate`` would divide by a subnormal phase (a retarget 300 s into a 1 s
#: skill threw it 1e44 m away). The step it would fade is then kept.
BLEND_PHASE_FLOOR = 1e-250


@dataclass(frozen=True)
class HandoverBlend:
    """Fades the acceleration mismatch at a skill switch, so acceleration stays continuous.

    A new skill starting from its predecessor's full state matches position and velocity by
    construction; its own acceleration at that state generally differs. This coupling adds
    the difference and lets it decay as ``(s / s0)^rate``: about ``exp(-t / t_blend)``
    (Nemec and Ude 2012 use a similar transient for DMP sequencing).

    Attributes
    ----------
    linear, angular : ndarray, shape (3,)
        Mismatch at the switch, m/s^2 and rad/s^2.
    phase0 : float
        Phase at the switch.
    rate : float
        Decay exponent in phase, ``1 / (alpha_s * blend_fraction)``.
    """

    linear: Array
    angular: Array
    phase0: float
    rate: float

    def acceleration(self, state: PoseState, target: PoseTarget) -> tuple[Array, Array]:
        """The remaining mismatch at ``state.phase``."""
        k = (max(state.phase, 1e-300) / self.phase0) ** self.rate
        return self.linear * k, self.angular * k


@dataclass
class PoseDMP:
    """A running pose DMP: model, target, state and coupling terms.

    Goal and ``tau`` can change while it runs. Start it from any full state
    (:meth:`start`) for a jump-free handover from the previous skill.
    """

    model: PoseModel
    target: PoseTarget
    state: PoseState
    couplings: list[CouplingTerm] = field(default_factory=list)
    #: The packed program and what it was packed from (compared by identity each step).
    _program: tuple[tuple[object, ...], Program] | None = field(
        default=None, init=False, repr=False, compare=False
    )

    @staticmethod
    def start(
        model: PoseModel,
        state: PoseState,
        goal_position: ArrayLike,
        goal_orientation: ArrayLike,
        tau: float | None = None,
        couplings: Sequence[CouplingTerm] = (),
        blend_fraction: float = 0.1,
        fresh_phase: bool = True,
    ) -> PoseDMP:
        """Start ``model`` from a handed-over full state.

        Parameters
        ----------
        model : PoseModel
        state : PoseState
            The previous skill's last full state (pose, velocities, accelerations).
        goal_position, goal_orientation : array_like
        tau : float, optional
        couplings : sequence of CouplingTerm
        blend_fraction : float
            Acceleration mismatch decays over about ``blend_fraction * tau``; 0 disables.
        fresh_phase : bool
            Start the new skill at phase 1 (a new motion) rather than the handed-over phase.
        """
        st = state.with_phase(1.0) if fresh_phase else state
        target = model.target(st.position, st.orientation, goal_position, goal_orientation, tau)
        dmp = PoseDMP(model, target, st, list(couplings))
        if blend_fraction > 0 and st.phase > BLEND_PHASE_FLOOR:
            acc, ang = pose_acceleration(st, model, target, dmp.couplings)
            dmp.couplings.append(
                HandoverBlend(
                    st.acceleration - acc,
                    st.angular_acceleration - ang,
                    st.phase,
                    1.0 / (model.params.alpha_s * blend_fraction),
                )
            )
        return dmp

    def set_goal(
        self,
        goal_position: ArrayLike,
        goal_orientation: ArrayLike | None = None,
        blend_fraction: float = 0.1,
    ) -> None:
        """Move the attractor while running; the forcing rescales to the new displacement.
        The acceleration's step at the switch fades over about ``blend_fraction * tau`` as a
        :meth:`start`'s does (0: the step is kept; a 2 cm goal shift had changed the
        acceleration by 0.2 m/s^2 in one step)."""
        q = self.target.goal_orientation if goal_orientation is None else goal_orientation
        target = self.model.target(
            self.target.start_position,
            self.target.start_orientation,
            goal_position,
            q,
            self.target.tau,
        )
        self._retarget(target, blend_fraction)

    def set_tau(self, tau: float, blend_fraction: float = 0.1) -> None:
        """Change the temporal scaling while running, the acceleration's step at the switch
        faded as :meth:`set_goal`'s."""
        if not (np.isfinite(tau) and tau > 0):
            raise ValueError(f"tau: expected a positive duration in s, got {tau!r}")
        self._retarget(replace(self.target, tau=float(tau)), blend_fraction)

    def _retarget(self, target: PoseTarget, blend_fraction: float) -> None:
        """Run on towards ``target``, with a :class:`HandoverBlend` of the acceleration the
        change would step (none for a ``blend_fraction`` of 0)."""
        if blend_fraction > 0.0 and self.state.phase > BLEND_PHASE_FLOOR:
            acc, ang = pose_acceleration(self.state, self.model, self.target, self.couplings)
            new_acc, new_ang = pose_acceleration(self.state, self.model, target, self.couplings)
            self.couplings.append(
                HandoverBlend(
                    acc - new_acc,
                    ang - new_ang,
                    self.state.phase,
                    1.0 / (self.model.params.alpha_s * blend_fraction),
                )
            )
        self.target = target

    def step(self, dt: float, measured: PoseState | None = None) -> PoseState:
        """Advance by ``dt`` from the measured state if given, else from the internal one.

        Compiled: the model and its couplings packed once (again after a goal, ``tau`` or
        coupling change) and run by :mod:`skills.interpreter`; :func:`pose_step` is the same
        step from the numpy references, and the tests hold the two within 1e-9.
        """
        current = measured or self.state
        x = np.empty(STATE_SIZE + 1)
        x[:STATE_SIZE] = state_values(current)
        x[STATE_SIZE] = current.phase
        key = (self.model, self.target, *self.couplings)
        packed = self._program
        if (
            packed is None
            or len(packed[0]) != len(key)
            or not all(a is b for a, b in zip(packed[0], key, strict=True))
        ):
            packed = self._program = (key, Program.single(self.model, self.target, key[2:], x))
        out = packed[1].pose_step(x, dt)
        self.state = state_from(out, float(out[STATE_SIZE]))
        return self.state

    def rollout(self, dt: float, n_steps: int | None = None) -> PoseTrajectory:
        """Predict the rest of the motion from the current state, open loop (state unchanged)."""
        return pose_rollout(self.model, self.target, self.state, dt, n_steps, self.couplings)
