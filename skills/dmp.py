"""Positional Dynamic Movement Primitives in any number of dimensions.

Transformation system (Ijspeert et al. 2013; the paper's eq. 1-2), with ``z = tau * ydot``::

    tau * zdot = alpha * (beta * (g - y) - z) + f(s) + tau^2 * c
    tau * ydot = z

so the physical acceleration is ``ydd = (alpha (beta (g - y) - tau yd) + f(s)) / tau^2 + c``,
with ``beta = alpha / 4`` (critical damping) and ``c`` the sum of coupling accelerations.
The forcing term is ``f(s) = s * M (sum_i psi_i(s) w_i / sum_i psi_i(s))`` with ``M`` the
spatial scaling of :mod:`skills.scaling` (``M = diag(g - y0)`` up to the reference, by default).

Integration is semi-implicit Euler: ``yd += ydd dt; y += yd dt``; the phase is integrated exactly.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from skills.basis import DEFAULT_ALPHA_S, RBFBasis, make_basis, phase, phase_step
from skills.demonstration import Demonstration
from skills.kernel import kernel
from skills.scaling import Scaling, scaling_matrix
from skills.types import Array


@dataclass(frozen=True)
class DMPParams:
    """Gains and learning settings shared by positional and orientation DMPs.

    Attributes
    ----------
    alpha : float
        Spring gain ``alpha``; ``beta = alpha / 4``.
    alpha_s : float
        Phase decay; ``s(tau) = exp(-alpha_s)``.
    n_basis : int
        Number of Gaussian basis functions per dimension.
    overlap : float
        Activation of a basis function at its neighbour's centre, in (0, 1).
    regularisation : float
        Ridge factor, relative to the mean diagonal of the normal matrix.
    """

    alpha: float = 25.0
    alpha_s: float = DEFAULT_ALPHA_S
    n_basis: int = 50
    overlap: float = 0.5
    regularisation: float = 1e-8

    def __post_init__(self) -> None:
        if not (np.isfinite(self.alpha) and self.alpha > 0):
            raise ValueError(f"alpha: expected a positive number, got {self.alpha!r}")
        if not (np.isfinite(self.alpha_s) and self.alpha_s > 0):
            raise ValueError(f"alpha_s: expected a positive number, got {self.alpha_s!r}")
        if not isinstance(self.n_basis, int | np.integer) or self.n_basis < 1:
            raise ValueError(f"n_basis: expected an integer >= 1, got {self.n_basis!r}")
        if not 0.0 < self.overlap < 1.0:
            raise ValueError(f"overlap: expected a value in (0, 1), got {self.overlap!r}")
        if not (np.isfinite(self.regularisation) and self.regularisation >= 0):
            raise ValueError(f"regularisation: expected a number >= 0, got {self.regularisation!r}")

    @property
    def beta(self) -> float:
        """``alpha / 4``: critically damped."""
        return self.alpha / 4.0

    def basis(self) -> RBFBasis:
        """The RBF basis these settings describe."""
        return make_basis(self.n_basis, self.alpha_s, self.overlap)


@dataclass(frozen=True)
class ForcingTerm:
    """A learnt forcing term ``f(s) = s * M(g - y0) * Phi(s) @ weights``.

    Attributes
    ----------
    weights : ndarray, shape (K, D)
    basis : RBFBasis
    reference : ndarray, shape (D,)
        The displacement ``g - y0`` the weights were learnt for.
    scaling : Scaling
    min_amplitude : float
    """

    weights: Array
    basis: RBFBasis
    reference: Array
    scaling: Scaling = Scaling.AMPLITUDE
    min_amplitude: float = 1e-3

    @property
    def dim(self) -> int:
        """Number of dimensions ``D``."""
        return int(self.weights.shape[1])

    def matrix(self, displacement: Array) -> Array:
        """Scaling matrix ``M``, shape (D, D), for a new ``g - y0``."""
        return scaling_matrix(self.scaling, displacement, self.reference, self.min_amplitude)

    def raw(self, s: ArrayLike) -> Array:
        """Unscaled ``s * Phi(s) @ weights``, shape ``(..., D)``."""
        s_arr = np.asarray(s, dtype=float)
        return s_arr[..., None] * (self.basis.normalised(s_arr) @ self.weights)

    def value(self, s: ArrayLike, matrix: Array) -> Array:
        """Forcing ``(..., D)`` at phase ``s`` for the scaling ``matrix`` (from :meth:`matrix`)."""
        return self.raw(s) @ matrix.T

    @staticmethod
    def zero(dim: int, basis: RBFBasis) -> ForcingTerm:
        """A forcing term that is identically zero: a plain critically damped spring."""
        return ForcingTerm(np.zeros((basis.size, dim)), basis, np.ones(dim), Scaling.NONE)


def design_matrix(t: Array, tau: float, basis: RBFBasis, alpha_s: float) -> tuple[Array, Array]:
    """Phase ``(N,)`` and regression design ``s * Phi(s)``, ``(N, K)``, for times since start."""
    s = phase(t - t[0], tau, alpha_s)
    return s, s[:, None] * basis.normalised(s)


def ridge(xs: Sequence[Array], fs: Sequence[Array], regularisation: float) -> Array:
    """Regularised least squares ``argmin_W sum_d |X_d W - F_d|^2 + lam |W|^2``.

    One linear solve for all dimensions and demonstrations; no loop over samples.

    Parameters
    ----------
    xs : sequence of ndarray, shapes (N_d, K)
    fs : sequence of ndarray, shapes (N_d, D)
    regularisation : float
        ``lam`` relative to the mean diagonal of ``X^T X``.

    Returns
    -------
    ndarray, shape (K, D)
    """
    x = np.concatenate(xs, axis=0)
    f = np.concatenate(fs, axis=0)
    gram = x.T @ x
    lam = regularisation * float(np.trace(gram)) / gram.shape[0]
    gram[np.diag_indices_from(gram)] += lam + 1e-300
    return np.linalg.solve(gram, x.T @ f)


def check_demonstrations(demos: Sequence[Demonstration], n_basis: int) -> None:
    if len(demos) == 0:
        raise ValueError("demos: expected at least one demonstration, got none")
    dims = {d.positions.shape[1] for d in demos}
    if len(dims) != 1:
        raise ValueError(
            f"demos: expected the same number of dimensions in each, got {sorted(dims)}"
        )
    for d in demos:
        if d.n_samples < n_basis:
            raise ValueError(
                f"{d.name}: t: expected at least n_basis={n_basis} samples to fit "
                f"{n_basis} basis functions, got {d.n_samples} (record at a higher rate or "
                "for longer; in Python, a model's n_basis argument fits fewer)"
            )


def _reference_inverse(
    term_scaling: Scaling, displacement: Array, reference: Array, min_amplitude: float, name: str
) -> Array:
    m = scaling_matrix(term_scaling, displacement, reference, min_amplitude)
    if abs(np.linalg.det(m)) < 1e-12:
        raise ValueError(
            f"{name}: positions: its displacement {np.round(displacement, 6).tolist()} cannot be "
            f"mapped onto the first demonstration's {np.round(reference, 6).tolist()} with "
            f"{term_scaling.value} scaling (a dimension moves in one and not the other)"
        )
    return np.linalg.inv(m)


def normalised_position_targets(
    demo: Demonstration,
    params: DMPParams,
    reference: Array,
    scaling: Scaling,
    min_amplitude: float,
) -> Array:
    """Target forcing ``(N, D)`` of one demonstration, mapped back to the reference displacement.

    ``f = tau^2 ydd - alpha (beta (g - y) - tau yd)`` with ``tau`` the demo's duration, then
    multiplied by ``M(g - y0)^-1`` so demonstrations of different sizes share one set of weights.
    """
    tau = demo.duration
    yd, ydd = demo.position_derivatives()
    y0, g = demo.positions[0], demo.positions[-1]
    f_target = tau * tau * ydd - params.alpha * (params.beta * (g - demo.positions) - tau * yd)
    m_inv = _reference_inverse(scaling, g - y0, reference, min_amplitude, demo.name)
    return f_target @ m_inv.T


@dataclass(frozen=True)
class PositionModel:
    """A learnt positional DMP: gains, forcing term and the demonstration's geometry.

    Attributes
    ----------
    params : DMPParams
    forcing : ForcingTerm
    demo_start, demo_goal : ndarray, shape (D,)
        Start and goal of the first demonstration.
    demo_tau : float
        Duration of the first demonstration, s.
    """

    params: DMPParams
    forcing: ForcingTerm
    demo_start: Array
    demo_goal: Array
    demo_tau: float


def fit_position(
    demos: Demonstration | Sequence[Demonstration],
    params: DMPParams | None = None,
    scaling: Scaling = Scaling.AMPLITUDE,
    min_amplitude: float = 1e-3,
) -> PositionModel:
    """Learn a positional DMP from one or more demonstrations.

    Each demonstration's target forcing ``tau^2 ydd - alpha (beta (g - y) - tau yd)`` is
    mapped back to the first demonstration's displacement, and all are fitted together by
    ridge regression.

    Parameters
    ----------
    demos : Demonstration or sequence of Demonstration
        Time stamps and positions ``(N, D)``; ``tau`` of each is its duration.
    params : DMPParams, optional
    scaling : Scaling
    min_amplitude : float
        Reference displacements below this do not scale (see :mod:`skills.scaling`).

    Returns
    -------
    PositionModel
    """
    p = params or DMPParams()
    demo_list = [demos] if isinstance(demos, Demonstration) else list(demos)
    check_demonstrations(demo_list, p.n_basis)
    basis = p.basis()
    first = demo_list[0]
    reference = first.positions[-1] - first.positions[0]
    xs, fs = [], []
    for d in demo_list:  # a loop over demonstrations, never over samples
        _, x = design_matrix(d.t, d.duration, basis, p.alpha_s)
        xs.append(x)
        fs.append(normalised_position_targets(d, p, reference, scaling, min_amplitude))
    weights = ridge(xs, fs, p.regularisation)
    forcing = ForcingTerm(weights, basis, reference, scaling, min_amplitude)
    return PositionModel(
        p, forcing, first.positions[0].copy(), first.positions[-1].copy(), first.duration
    )


@dataclass(frozen=True)
class DMPState:
    """Full state of a positional DMP: the handover between skills.

    Attributes
    ----------
    position, velocity, acceleration : ndarray, shape (D,)
        m, m/s, m/s^2.
    phase : float
        Canonical phase ``s`` in (0, 1].
    """

    position: Array
    velocity: Array
    acceleration: Array
    phase: float = 1.0

    @staticmethod
    def at_rest(position: ArrayLike) -> DMPState:
        """Zero velocity and acceleration at ``position``, phase 1."""
        y = np.asarray(position, dtype=float).copy()
        return DMPState(y, np.zeros_like(y), np.zeros_like(y), 1.0)


def position_acceleration(
    y: Array,
    yd: Array,
    s: float,
    goal: Array,
    tau: float,
    forcing: Array,
    alpha: float,
    beta: float,
) -> Array:
    """Transformation-system acceleration ``(D,)`` without coupling terms."""
    return (alpha * (beta * (goal - y) - tau * yd) + forcing) / (tau * tau)


def position_step(
    state: DMPState,
    model: PositionModel,
    goal: Array,
    matrix: Array,
    tau: float,
    dt: float,
    coupling: Array | None = None,
) -> DMPState:
    """Advance a positional DMP by ``dt`` from ``state`` (closed loop: state may be measured).

    Parameters
    ----------
    state : DMPState
    model : PositionModel
    goal : ndarray, shape (D,)
    matrix : ndarray, shape (D, D)
        Forcing scaling ``model.forcing.matrix(goal - start)``.
    tau : float
        Temporal scaling, s (> 0).
    dt : float
        Step, s.
    coupling : ndarray, shape (D,), optional
        Sum of coupling accelerations, m/s^2.
    """
    p = model.params
    f = model.forcing.value(state.phase, matrix)
    ydd = position_acceleration(
        state.position, state.velocity, state.phase, goal, tau, f, p.alpha, p.beta
    )
    if coupling is not None:
        ydd = ydd + coupling
    yd = state.velocity + ydd * dt
    y = state.position + yd * dt
    return DMPState(y, yd, ydd, phase_step(state.phase, dt, tau, p.alpha_s))


@dataclass(frozen=True)
class Trajectory:
    """A sampled positional trajectory; every array has the same first length ``N``.

    Attributes
    ----------
    t : ndarray, shape (N,)
    positions, velocities, accelerations : ndarray, shape (N, D)
    phase : ndarray, shape (N,)
    """

    t: Array
    positions: Array
    velocities: Array
    accelerations: Array
    phase: Array

    def state(self, i: int) -> DMPState:
        """Full state at sample ``i``."""
        return DMPState(
            self.positions[i].copy(),
            self.velocities[i].copy(),
            self.accelerations[i].copy(),
            float(self.phase[i]),
        )


@kernel
def second_order_filter(a: Array, b0: float, u: Array, z: Array, out: Array) -> None:
    """``out[k] = b0 u[k] - a[1] out[k-1] - a[2] out[k-2]`` per column, from the state ``z``.

    The filter :func:`scipy.signal.lfilter` applies for ``b = [b0]``, ``a = [1, a1, a2]``,
    in its own form (direct form II transposed, the numerator padded with zero taps to the
    denominator's length) and order of operations, so each output rounds as lfilter's does:
    ``y = z0 + b0 u; z0 = z1 + u 0 - a1 y; z1 = u 0 - a2 y``.

    Parameters
    ----------
    a : ndarray, shape (3,)
        ``[1, a1, a2]``.
    b0 : float
    u : ndarray, shape (N, D)
        Inputs.
    z : ndarray, shape (2, D)
        Initial state (lfilter's ``zi``); left as it was.
    out : ndarray, shape (N, D)
        Written with the outputs.
    """
    zero = 0.0  # the padded taps b1 = b2 = 0, multiplied as lfilter multiplies them
    for d in range(u.shape[1]):
        z0, z1 = z[0, d], z[1, d]
        for k in range(u.shape[0]):
            x = u[k, d]
            y = z0 + b0 * x
            z0 = z1 + x * zero - y * a[1]
            z1 = x * zero - y * a[2]
            out[k, d] = y


def linear_rollout(
    y0: Array,
    yd0: Array,
    goal: Array,
    drive: Array,
    alpha: float,
    beta: float,
    tau: float,
    dt: float,
) -> tuple[Array, Array, Array]:
    """Semi-implicit Euler rollout of ``ydd = K (g - y) - D yd + u_k`` for all steps at once.

    The recurrence for the error ``e = y - g`` is second order and linear::

        e[k+2] = (2 - D dt - K dt^2) e[k+1] - (1 - D dt) e[k] + dt^2 u[k+1]

    so a second-order linear filter solves it in compiled code (:func:`second_order_filter`,
    the filter :func:`scipy.signal.lfilter` would apply), matching step-by-step integration
    to rounding error.

    Parameters
    ----------
    y0, yd0, goal : ndarray, shape (D,)
    drive : ndarray, shape (N, D)
        ``u_k``: forcing over ``tau^2`` plus coupling accelerations at each step.
    alpha, beta, tau, dt : float

    Returns
    -------
    positions, velocities, accelerations : ndarray, shape (N + 1, D), (N + 1, D), (N, D)
        States before and after each of the ``N`` steps, and each step's acceleration.
    """
    n = drive.shape[0]
    k_gain = alpha * beta / (tau * tau)
    d_gain = alpha / tau
    e0 = y0 - goal
    acc0 = -k_gain * e0 - d_gain * yd0 + drive[0]
    yd1 = yd0 + acc0 * dt
    e1 = e0 + yd1 * dt
    a = np.array([1.0, -(2.0 - d_gain * dt - k_gain * dt * dt), 1.0 - d_gain * dt])
    b = np.array([dt * dt])
    e = np.empty((n + 1, y0.shape[0]))
    e[0], e[1] = e0, e1
    if n > 1:
        # Outputs e[2..n] driven by u[1..n-1], seeded with e[1], e[0] as past outputs.
        # Transposed direct-form state for past outputs e[1], e[0] (b has a single tap).
        zi = np.stack((-a[1] * e1 - a[2] * e0, -a[2] * e1))
        # Not scipy.signal.lfilter: importing scipy.signal (and scipy.stats with it) took a
        # second of every run, for this one filter.
        second_order_filter(a, float(b[0]), np.ascontiguousarray(drive[1:]), zi, e[2:])
    y = e + goal
    yd = np.empty_like(y)
    yd[0] = yd0
    yd[1:] = np.diff(y, axis=0) / dt
    ydd = np.diff(yd, axis=0) / dt
    return y, yd, ydd


def position_rollout(
    model: PositionModel,
    start: DMPState,
    goal: ArrayLike,
    tau: float | None = None,
    dt: float = 0.01,
    n_steps: int | None = None,
    y0: ArrayLike | None = None,
) -> Trajectory:
    """Open-loop rollout, vectorised over time.

    Parameters
    ----------
    model : PositionModel
    start : DMPState
        Initial full state (the phase may be mid-motion).
    goal : array_like, shape (D,)
    tau : float, optional
        Defaults to the demonstration's duration.
    dt : float
        Step, s.
    n_steps : int, optional
        Defaults to ``1.5 * tau / dt``, enough to settle.
    y0 : array_like, shape (D,), optional
        Start the forcing term is scaled from; defaults to ``start.position``.

    Returns
    -------
    Trajectory
        ``n_steps + 1`` samples including the start.
    """
    p = model.params
    tau_v = float(tau if tau is not None else model.demo_tau)
    if not tau_v > 0:
        raise ValueError(f"tau: expected a positive duration, got {tau_v!r}")
    g = np.asarray(goal, dtype=float)
    origin = start.position if y0 is None else np.asarray(y0, dtype=float)
    n = int(n_steps if n_steps is not None else np.ceil(1.5 * tau_v / dt))
    k = np.arange(n + 1)
    s = start.phase * np.exp(-p.alpha_s * k * dt / tau_v)
    matrix = model.forcing.matrix(g - origin)
    drive = model.forcing.value(s[:-1], matrix) / (tau_v * tau_v)
    y, yd, ydd_steps = linear_rollout(
        start.position, start.velocity, g, drive, p.alpha, p.beta, tau_v, dt
    )
    ydd = np.empty_like(y)
    ydd[:-1] = ydd_steps
    last = position_acceleration(
        y[-1], yd[-1], s[-1], g, tau_v, model.forcing.value(s[-1], matrix), p.alpha, p.beta
    )
    ydd[-1] = last
    return Trajectory(k * dt, y, yd, ydd, s)


PositionCoupling = Callable[[DMPState], Array]
"""A coupling term for a generic positional DMP: full state -> acceleration ``(D,)``."""


@dataclass
class PositionDMP:
    """Stateful wrapper: a learnt model, a goal, ``tau``, the current state and couplings.

    Goal and ``tau`` may change while it runs; call :meth:`step` with a measured state to
    close the loop, or without to integrate open loop.
    """

    model: PositionModel
    goal: Array
    tau: float
    state: DMPState
    start: Array = field(default_factory=lambda: np.zeros(0))
    couplings: list[PositionCoupling] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.goal = np.asarray(self.goal, dtype=float)
        if self.start.size == 0:
            self.start = self.state.position.copy()
        self._matrix = self.model.forcing.matrix(self.goal - self.start)

    @staticmethod
    def from_model(
        model: PositionModel,
        goal: ArrayLike,
        state: DMPState | None = None,
        tau: float | None = None,
    ) -> PositionDMP:
        """Start ``model`` from ``state`` (default: at rest at the demo start) towards ``goal``."""
        st = state or DMPState.at_rest(model.demo_start)
        return PositionDMP(model, np.asarray(goal, dtype=float), tau or model.demo_tau, st)

    def set_goal(self, goal: ArrayLike) -> None:
        """Move the attractor; the forcing term rescales to the new displacement."""
        self.goal = np.asarray(goal, dtype=float)
        self._matrix = self.model.forcing.matrix(self.goal - self.start)

    def step(self, dt: float, measured: DMPState | None = None) -> DMPState:
        """Advance by ``dt`` from the measured state if given, else from the internal one."""
        current = measured or self.state
        coupling = None
        if self.couplings:
            coupling = np.sum([c(current) for c in self.couplings], axis=0)
        self.state = position_step(
            current, self.model, self.goal, self._matrix, self.tau, dt, coupling
        )
        return self.state
