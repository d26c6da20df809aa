"""Pose DMPs: three positional DMPs and one quaternion DMP sharing one phase.

This is the unit the paper composes: an absolute skill moves the object's pose, a relative
skill moves a palm's pose in the object frame. Position and orientation outputs always have
the same length because they are integrated in the same loop over the same phase.

Pure functions first (:func:`pose_step`, :func:`pose_rollout`, :func:`fit_pose`), then the
thin stateful :class:`PoseDMP`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from functools import cached_property
from itertools import pairwise
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from skills import quaternion as quat
from skills.basis import DEFAULT_ALPHA_S, RBFBasis, phase_step
from skills.coupling import AccelerationFloats, CouplingTerm
from skills.demonstration import Demonstration
from skills.dmp import (
    DMPParams,
    ForcingTerm,
    PositionModel,
    check_demonstrations,
    design_matrix,
    linear_rollout,
    normalised_position_targets,
    ridge,
)
from skills.quaternion_dmp import (
    OrientationModel,
    integrate_orientation,
    normalised_orientation_targets,
    orientation_reference,
)
from skills.scaling import Scaling
from skills.types import Array


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
        y = np.array(position, dtype=float)
        if y.shape != (3,) or not np.all(np.isfinite(y)):
            raise ValueError(f"position: expected 3 finite numbers, got {position!r}")
        q = quat.as_quaternions(orientation, "orientation")
        if q.shape != (4,):
            raise ValueError(f"orientation: expected one quaternion (4,), got shape {q.shape}")
        z = np.zeros(3)
        return PoseState(y, z, z.copy(), q, z.copy(), z.copy(), 1.0)

    def twist(self) -> Array:
        """Linear and angular velocity stacked, shape (6,)."""
        return np.concatenate((self.velocity, self.angular_velocity))

    def with_phase(self, s: float) -> PoseState:
        """The same pose and motion at another phase (a fresh skill starts at ``s = 1``)."""
        return self._replace(phase=float(s))


#: A pose state's six arrays end to end, 19 floats: position, velocity, acceleration,
#: orientation, angular velocity, angular acceleration (the layout of :func:`state_from`).
StateValues = tuple[float, ...]
STATE_SIZE = 19


def state_values(state: PoseState) -> StateValues:
    """``state``'s arrays end to end as floats (:data:`StateValues`)."""
    return tuple(np.concatenate(state[:6]).tolist())


def _field_slices(at: int) -> tuple[slice, ...]:
    bounds = (0, 3, 6, 9, 13, 16, 19)
    return tuple(slice(at + a, at + b) for a, b in pairwise(bounds))


# Built once: a state is cut out of a buffer every control tick.
_STATE_SLICES = {at: _field_slices(at) for at in (0, STATE_SIZE, 2 * STATE_SIZE)}


def state_from(values: Array, phase: float, at: int = 0) -> PoseState:
    """The :class:`PoseState` whose arrays are views of ``values[at:at + 19]``."""
    y, yd, ydd, q, w, wd = _STATE_SLICES.get(at) or _field_slices(at)
    return PoseState(values[y], values[yd], values[ydd], values[q], values[w], values[wd], phase)


class PoseFloats(NamedTuple):
    """A pose state's pose, twist and phase as Python floats, read once per control tick.

    What the scalar paths read (:class:`skills.coupling.ScalarCouplingTerm`, the dual-arm
    composer): on 3-vectors numpy's per-call cost exceeds the arithmetic.

    Attributes
    ----------
    position, velocity, angular_velocity : list of 3 floats
        m, m/s, rad/s.
    orientation : tuple of 4 floats
        ``(x, y, z, w)``.
    phase : float
    source : PoseState
        The state they were read from (for terms that only take arrays).
    """

    position: list[float]
    orientation: quat.Quat
    velocity: list[float]
    angular_velocity: list[float]
    phase: float
    source: PoseState

    @staticmethod
    def of(state: PoseState) -> PoseFloats:
        """Read ``state``'s pose, twist and phase."""
        return PoseFloats(
            state.position.tolist(),
            quat.as_tuple(state.orientation),
            state.velocity.tolist(),
            state.angular_velocity.tolist(),
            state.phase,
            state,
        )


def integrate_floats(pose: PoseFloats, acc: Sequence[float], dt: float) -> StateValues:
    """One step of semi-implicit Euler and the exponential map, in floats.

    ``v += a dt, y += v dt`` and ``omega += alpha dt, q = exp(dt/2 omega) q``, for the
    accelerations ``acc`` (linear then angular, 6 floats); returns the new state's values,
    whose accelerations are ``acc``.
    """
    y0, y1, y2 = pose.position
    v0, v1, v2 = pose.velocity
    w0, w1, w2 = pose.angular_velocity
    a0, a1, a2, b0, b1, b2 = acc
    v0 += a0 * dt
    v1 += a1 * dt
    v2 += a2 * dt
    w0 += b0 * dt
    w1 += b1 * dt
    w2 += b2 * dt
    q = quat.integrate_scalar(pose.orientation, (w0, w1, w2), dt)
    return (
        y0 + v0 * dt,
        y1 + v1 * dt,
        y2 + v2 * dt,
        v0,
        v1,
        v2,
        a0,
        a1,
        a2,
        *q,
        w0,
        w1,
        w2,
        b0,
        b1,
        b2,
    )


@dataclass(frozen=True)
class PoseTarget:
    """Where a pose DMP goes and how fast: start, goal, ``tau`` and the forcing scalings.

    Build with :meth:`PoseModel.target` so the scaling matrices match the model.

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

    @cached_property
    def goal_tuple(self) -> quat.Quat:
        """Goal orientation as floats, for the scalar quaternion maths of the step."""
        x, y, z, w = self.goal_orientation.tolist()
        return (x, y, z, w)

    @cached_property
    def goal_position_tuple(self) -> quat.Vec3:
        """Goal position as floats, for the scalar maths of the step."""
        x, y, z = self.goal_position.tolist()
        return (x, y, z)


@dataclass(frozen=True)
class PoseModel:
    """A learnt pose DMP: a positional and an orientation model with one basis and phase."""

    position: PositionModel
    orientation: OrientationModel

    @property
    def params(self) -> DMPParams:
        """Shared gains and basis settings."""
        return self.position.params

    @property
    def demo_tau(self) -> float:
        """Duration of the first demonstration, s."""
        return self.position.demo_tau

    def target(
        self,
        start_position: ArrayLike,
        start_orientation: ArrayLike,
        goal_position: ArrayLike,
        goal_orientation: ArrayLike,
        tau: float | None = None,
    ) -> PoseTarget:
        """A validated target for this model.

        Raises
        ------
        ValueError
            On non-finite positions, zero-norm quaternions or a non-positive ``tau``.
        """
        y0 = _vec3(start_position, "start_position")
        g = _vec3(goal_position, "goal_position")
        q0 = quat.as_quaternions(start_orientation, "start_orientation")
        qg = quat.as_quaternions(goal_orientation, "goal_orientation")
        t = float(self.demo_tau if tau is None else tau)
        if not (np.isfinite(t) and t > 0):
            raise ValueError(f"tau: expected a positive duration in s, got {tau!r}")
        m_pos = self.position.forcing.matrix(g - y0)
        m_ori = self.orientation.matrix(q0, qg)
        effective = np.hstack(
            (
                self.position.forcing.weights @ m_pos.T,
                self.orientation.forcing.weights @ m_ori.T,
                np.ones((self.position.forcing.basis.size, 1)),
            )
        )
        return PoseTarget(y0, q0, g, qg, t, m_pos, m_ori, effective)

    @cached_property
    def stacked_weights(self) -> Array:
        """Position and orientation weights side by side, shape (K, 6)."""
        return np.hstack((self.position.forcing.weights, self.orientation.forcing.weights))

    @staticmethod
    def still(params: DMPParams | None = None) -> PoseModel:
        """A model with zero forcing: a critically damped spring to the goal pose."""
        p = params or DMPParams()
        basis = p.basis()
        zero = ForcingTerm.zero(3, basis)
        pos = PositionModel(p, zero, np.zeros(3), np.zeros(3), 1.0)
        ori = OrientationModel(p, zero, quat.IDENTITY.copy(), quat.IDENTITY.copy(), 1.0)
        return PoseModel(pos, ori)


def _vec3(v: ArrayLike, name: str) -> Array:
    arr = np.array(v, dtype=float)
    if arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise ValueError(f"{name}: expected 3 finite numbers, got {v!r}")
    return arr


def fit_pose(
    demos: Demonstration | Sequence[Demonstration],
    params: DMPParams | None = None,
    position_scaling: Scaling = Scaling.AMPLITUDE,
    orientation_scaling: Scaling = Scaling.AMPLITUDE,
    min_amplitude: float = 1e-3,
    min_rotation: float = 1e-2,
) -> PoseModel:
    """Learn a pose DMP from demonstrations with 3-D positions and orientations.

    Positions and orientations share one phase, one basis and one design matrix, so all
    six dimensions are fitted by a single ridge solve.

    Parameters
    ----------
    demos : Demonstration or sequence of Demonstration
    params : DMPParams, optional
    position_scaling, orientation_scaling : Scaling
    min_amplitude : float
        Reference displacement (m) below which a position axis does not scale.
    min_rotation : float
        Reference rotation (rad) below which a rotation axis does not scale.

    Raises
    ------
    ValueError
        If a demonstration has no orientations or its positions are not 3-D.
    """
    demo_list = [demos] if isinstance(demos, Demonstration) else list(demos)
    for d in demo_list:
        if d.positions.shape[1] != 3:
            raise ValueError(f"{d.name}: positions: expected shape (N, 3), got {d.positions.shape}")
        if d.orientations is None:
            raise ValueError(f"{d.name}: orientations: expected (N, 4) quaternions, got none")
    p = params or DMPParams()
    check_demonstrations(demo_list, p.n_basis)
    basis = p.basis()
    first = demo_list[0]
    ref_pos = first.positions[-1] - first.positions[0]
    ref_ori = orientation_reference(first)
    xs, fs = [], []
    for d in demo_list:  # one design matrix per demonstration serves all six dimensions
        _, x = design_matrix(d.t, d.duration, basis, p.alpha_s)
        xs.append(x)
        fs.append(
            np.hstack(
                (
                    normalised_position_targets(d, p, ref_pos, position_scaling, min_amplitude),
                    normalised_orientation_targets(
                        d, p, ref_ori, orientation_scaling, min_rotation
                    ),
                )
            )
        )
    w = ridge(xs, fs, p.regularisation)
    pos = PositionModel(
        p,
        ForcingTerm(w[:, :3].copy(), basis, ref_pos, position_scaling, min_amplitude),
        first.positions[0].copy(),
        first.positions[-1].copy(),
        first.duration,
    )
    assert first.orientations is not None
    ori = OrientationModel(
        p,
        ForcingTerm(w[:, 3:].copy(), basis, ref_ori, orientation_scaling, min_rotation),
        first.orientations[0].copy(),
        first.orientations[-1].copy(),
        first.duration,
    )
    return PoseModel(pos, ori)


class LearntForcing:
    """The learnt RBF forcing term of ``model`` as a :class:`CouplingTerm`.

    Used to compose a learnt skill with others on a shared transformation system: its forcing
    is scaled for the running target's start and goal with ``model``'s own scaling, and read
    at the running phase.

    Parameters
    ----------
    model : PoseModel
    basis : RBFBasis, optional
        Read the activations from this instance of the model's basis functions (same centres
        and widths): terms on one basis at one phase then share a single evaluation per step.
    """

    def __init__(self, model: PoseModel, basis: RBFBasis | None = None) -> None:
        own = model.position.forcing.basis
        if basis is not None and not basis.same_as(own):
            raise ValueError(
                f"basis: expected the model's basis functions ({own.size} with the same centres "
                f"and widths), got {basis.size} that differ"
            )
        self.model = model
        self.basis = basis or own
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
        f = self._forcing(state.phase, target)
        return np.array(f[:3]), np.array(f[3:])

    def scalar_acceleration(self, pose: PoseFloats, target: PoseTarget) -> AccelerationFloats:
        """:meth:`acceleration` as floats."""
        return self._forcing(pose.phase, target)

    def _forcing(self, s: float, target: PoseTarget) -> AccelerationFloats:
        # f(s) / tau^2 = s (psi @ W) / (sum(psi) tau^2), the scaled weights W from own_target.
        own = self.own_target(target)
        raw = (self.basis.activations_at(s) @ own.effective_weights).tolist()
        k = s / (max(raw[6], 1e-300) * own.tau * own.tau)
        return (raw[0] * k, raw[1] * k, raw[2] * k, raw[3] * k, raw[4] * k, raw[5] * k)


class Saturated:
    """The weighted sum of several coupling terms, its norms limited.

    A held object can only follow accelerations its grip transmits: friction bounds the
    force the palms can add. Avoidance terms that grow without bound near an obstacle (a
    ``1/p^2`` potential) are summed here and scaled down as a whole when the sum exceeds the
    limits, keeping its direction.

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
        self.terms = [Weighted(t, float(w)) for t, w in terms]
        self.max_linear = float(max_linear)
        self.max_angular = float(max_angular)
        self.fade_phase = float(fade_phase)

    def acceleration(self, state: PoseState, target: PoseTarget) -> tuple[Array, Array]:
        """The limited sum (linear m/s^2, angular rad/s^2), faded out below ``fade_phase``."""
        if self.fade_phase > 0.0 and state.phase < self.fade_phase:
            # Like the learnt forcing, shaping terms hand the end of the motion to the
            # attractor: near the goal they would fight it (a limit cycle next to an obstacle).
            gate = (state.phase / self.fade_phase) ** 2
            if gate < 0.05:
                return np.zeros(3), np.zeros(3)
        else:
            gate = 1.0
        lin, ang = sum_couplings(self.terms, state, target)
        if gate != 1.0:
            lin, ang = lin * gate, ang * gate
        n_lin = float(np.sqrt(lin @ lin))
        n_ang = float(np.sqrt(ang @ ang))
        if n_lin > self.max_linear:
            lin = lin * (self.max_linear / n_lin)
        if n_ang > self.max_angular:
            ang = ang * (self.max_angular / n_ang)
        return lin, ang

    def replace_term(self, old: CouplingTerm, new: CouplingTerm) -> None:
        """Swap one inner term (e.g. avoidance on fresh link points), keeping its weight."""
        self.terms = [Weighted(new, w.weight) if w.term is old else w for w in self.terms]


@dataclass(frozen=True)
class Weighted:
    """A coupling term scaled by a composition weight (the paper's ``w_j`` / ``w_k``)."""

    term: CouplingTerm
    weight: float

    def acceleration(self, state: PoseState, target: PoseTarget) -> tuple[Array, Array]:
        """``weight`` times the term's accelerations."""
        lin, ang = self.term.acceleration(state, target)
        if self.weight == 1.0:
            return lin, ang
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
    lin, ang = _accelerations(state, model, target, couplings)
    return np.array(lin), np.array(ang)


def _accelerations(
    state: PoseState,
    model: PoseModel,
    target: PoseTarget,
    couplings: Sequence[CouplingTerm],
) -> tuple[list[float], list[float]]:
    acc = transformation_floats(PoseFloats.of(state), model, target)
    add_couplings(acc, couplings, state, target)
    return acc[:3], acc[3:]


def transformation_floats(pose: PoseFloats, model: PoseModel, target: PoseTarget) -> list[float]:
    """The transformation system's accelerations with the model's forcing, in floats.

    :func:`attractor_floats` plus ``f(s) / tau^2`` (``f`` from ``target.effective_weights``),
    linear then angular (6 floats). Floats after the one basis product: numpy's per-call
    overhead would otherwise dominate the arithmetic on 3-vectors.
    """
    a0, a1, a2, b0, b1, b2 = attractor_floats(pose, model.params, target)
    tau = target.tau
    s = pose.phase
    raw = (model.position.forcing.basis.activations_at(s) @ target.effective_weights).tolist()
    k = s * (1.0 / (tau * tau)) / max(raw[6], 1e-300)
    return [
        a0 + k * raw[0],
        a1 + k * raw[1],
        a2 + k * raw[2],
        b0 + k * raw[3],
        b1 + k * raw[4],
        b2 + k * raw[5],
    ]


def attractor_floats(pose: PoseFloats, params: DMPParams, target: PoseTarget) -> list[float]:
    """The spring-damper towards the goal, linear then angular (6 floats).

    ``alpha (beta (g - y) - tau yd) / tau^2`` for position and the same with the short-way
    rotation error ``2 log(g conj(q))`` for orientation.
    """
    tau = target.tau
    kp = params.alpha * params.beta * (1.0 / (tau * tau))
    kd = params.alpha / tau
    y0, y1, y2 = pose.position
    v0, v1, v2 = pose.velocity
    w0, w1, w2 = pose.angular_velocity
    g0, g1, g2 = target.goal_position_tuple
    e0, e1, e2 = quat.rotation_error_scalar(target.goal_tuple, pose.orientation)
    return [
        kp * (g0 - y0) - kd * v0,
        kp * (g1 - y1) - kd * v1,
        kp * (g2 - y2) - kd * v2,
        kp * e0 - kd * w0,
        kp * e1 - kd * w1,
        kp * e2 - kd * w2,
    ]


def add_couplings(
    acc: list[float], couplings: Sequence[CouplingTerm], state: PoseState, target: PoseTarget
) -> None:
    """Add each coupling's accelerations at ``state`` to ``acc`` (6 floats), in order."""
    for c in couplings:
        c_lin, c_ang = c.acceleration(state, target)
        l0, l1, l2 = c_lin.tolist()
        r0, r1, r2 = c_ang.tolist()
        acc[0] += l0
        acc[1] += l1
        acc[2] += l2
        acc[3] += r0
        acc[4] += r1
        acc[5] += r2


def pose_step(
    state: PoseState,
    model: PoseModel,
    target: PoseTarget,
    dt: float,
    couplings: Sequence[CouplingTerm] = (),
) -> PoseState:
    """Advance a pose DMP by ``dt`` (closed loop: ``state`` may be the measured one).

    Semi-implicit Euler for position and angular velocity, the exponential map for the
    quaternion, the exact solution for the phase.

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
    # One function, floats after the basis product: this runs every control step, and on a
    # 3-vector numpy's per-call overhead costs more than the arithmetic. The same operations
    # as transformation_floats, add_couplings and integrate_floats, inlined.
    p = model.params
    tau = target.tau
    s = state.phase
    raw = (model.position.forcing.basis.activations_at(s) @ target.effective_weights).tolist()
    inv_tau2 = 1.0 / (tau * tau)
    k = s * inv_tau2 / max(raw[6], 1e-300)
    kp = p.alpha * p.beta * inv_tau2
    kd = p.alpha / tau
    y0, y1, y2 = state.position.tolist()
    v0, v1, v2 = state.velocity.tolist()
    w0, w1, w2 = state.angular_velocity.tolist()
    qx, qy, qz, qw = state.orientation.tolist()
    g0, g1, g2 = target.goal_position_tuple
    e0, e1, e2 = quat.rotation_error_scalar(target.goal_tuple, (qx, qy, qz, qw))
    a0 = kp * (g0 - y0) - kd * v0 + k * raw[0]
    a1 = kp * (g1 - y1) - kd * v1 + k * raw[1]
    a2 = kp * (g2 - y2) - kd * v2 + k * raw[2]
    b0 = kp * e0 - kd * w0 + k * raw[3]
    b1 = kp * e1 - kd * w1 + k * raw[4]
    b2 = kp * e2 - kd * w2 + k * raw[5]
    for c in couplings:
        c_lin, c_ang = c.acceleration(state, target)
        l0, l1, l2 = c_lin.tolist()
        r0, r1, r2 = c_ang.tolist()
        a0 += l0
        a1 += l1
        a2 += l2
        b0 += r0
        b1 += r1
        b2 += r2
    v0 += a0 * dt
    v1 += a1 * dt
    v2 += a2 * dt
    w0 += b0 * dt
    w1 += b1 * dt
    w2 += b2 * dt
    q = quat.integrate_scalar((qx, qy, qz, qw), (w0, w1, w2), dt)
    # One allocation for the whole state; the fields are views into it.
    y0, y1, y2 = y0 + v0 * dt, y1 + v1 * dt, y2 + v2 * dt
    buf = np.array((y0, y1, y2, v0, v1, v2, a0, a1, a2, *q, w0, w1, w2, b0, b1, b2))
    return state_from(buf, phase_step(s, dt, tau, p.alpha_s))


def coupled_step(
    state: PoseState,
    target: PoseTarget,
    dt: float,
    couplings: Sequence[CouplingTerm],
    alpha_s: float = DEFAULT_ALPHA_S,
) -> PoseState:
    """Advance a pose driven by coupling terms alone (no attractor of its own).

    Relative-space skills such as grasp maintenance carry their own reference; this integrates
    their summed accelerations with the same scheme as :func:`pose_step`.
    """
    acc = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    add_couplings(acc, couplings, state, target)
    return state_from(
        np.array(integrate_floats(PoseFloats.of(state), acc, dt)),
        phase_step(state.phase, dt, target.tau, alpha_s),
    )


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
        if blend_fraction > 0:
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

    def set_goal(self, goal_position: ArrayLike, goal_orientation: ArrayLike | None = None) -> None:
        """Move the attractor while running; the forcing rescales to the new displacement."""
        q = self.target.goal_orientation if goal_orientation is None else goal_orientation
        self.target = self.model.target(
            self.target.start_position,
            self.target.start_orientation,
            goal_position,
            q,
            self.target.tau,
        )

    def set_tau(self, tau: float) -> None:
        """Change the temporal scaling while running."""
        if not (np.isfinite(tau) and tau > 0):
            raise ValueError(f"tau: expected a positive duration in s, got {tau!r}")
        self.target = replace(self.target, tau=float(tau))

    def step(self, dt: float, measured: PoseState | None = None) -> PoseState:
        """Advance by ``dt`` from the measured state if given, else from the internal one."""
        self.state = pose_step(measured or self.state, self.model, self.target, dt, self.couplings)
        return self.state

    def rollout(self, dt: float, n_steps: int | None = None) -> PoseTrajectory:
        """Predict the rest of the motion from the current state, open loop (state unchanged)."""
        return pose_rollout(self.model, self.target, self.state, dt, n_steps, self.couplings)
