"""Learning the steering parameters from avoidance demonstrations (Rai et al. 2014).

The coupling a demonstration shows is what its acceleration has beyond the base DMP's:

    c_demo = ydd_demo - (alpha (beta (g - y) - tau yd) + f(s)) / tau^2

evaluated on the demonstrated ``y``, ``yd`` at the phase of each sample. ``gamma``, ``beta``
and ``k`` of :class:`~skills.couplings.steering.ObstacleSteering` are then the bounded
nonlinear least-squares fit of the steering law to ``c_demo`` over all samples and axes.
A coarse grid over ``(beta, k)``, with the best ``gamma`` for each in closed form (the law is
linear in ``gamma``), picks the starting point, so the fit does not depend on a guess.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from skills import quaternion as quat
from skills.couplings._checks import non_negative, vector
from skills.couplings.steering import ObstacleSteering, steering_accelerations
from skills.demonstration import Demonstration
from skills.dmp import DMPParams
from skills.pose_model import PoseModel
from skills.types import Array

_BETA_GRID = (0.25, 0.5, 1.0, 2.0, 4.0, 8.0)
_K_GRID = (0.0, 3.0, 10.0, 30.0, 100.0, 300.0, 1000.0)


@dataclass(frozen=True)
class AvoidanceDemo:
    """One demonstration of moving around obstacles, with the obstacles it avoided.

    Attributes
    ----------
    demo : Demonstration
        Positions (N, 3), m, in the frame of the obstacles.
    centres : ndarray, shape (M, 3)
        Obstacle centres, m.
    radii : ndarray, shape (M,)
        Obstacle radii, m.
    tau : float or None
        The base DMP's temporal scaling, s; None uses the demonstration's duration. The base
        motion starts at the first sample and ends at the last.
    """

    demo: Demonstration
    centres: Array
    radii: Array
    tau: float | None = None

    @staticmethod
    def create(
        demo: Demonstration, centres: ArrayLike, radii: ArrayLike, tau: float | None = None
    ) -> AvoidanceDemo:
        """Validate and build; ``centres`` (M, 3) or (3,), ``radii`` (M,) or scalar."""
        if demo.positions.shape[1] != 3:
            raise ValueError(
                f"{demo.name}: positions: expected shape (N, 3), got {demo.positions.shape}"
            )
        c = vector(np.reshape(np.asarray(centres, dtype=float), (-1, 3)), (-1, 3), "centres")
        r = vector(np.reshape(np.asarray(radii, dtype=float), (-1,)), (-1,), "radii")
        if r.shape[0] != c.shape[0]:
            raise ValueError(
                f"radii: expected one radius per centre ({c.shape[0]}), got {r.shape[0]}"
            )
        if tau is not None and not (math.isfinite(tau) and tau > 0):
            raise ValueError(f"tau: expected a positive duration in s, got {tau!r}")
        return AvoidanceDemo(demo, c, r, tau)


@dataclass(frozen=True)
class SteeringFit:
    """Fitted steering and how well it explains the demonstrated coupling.

    Attributes
    ----------
    steering : ObstacleSteering
        Fitted ``gamma`` (1/s), ``beta`` (1/rad), ``k`` (1/m^2), with the first
        demonstration's obstacles.
    residual_rms : float
        RMS of ``c_fit - c_demo`` over samples and axes, m/s^2.
    relative_residual : float
        ``residual_rms / RMS(c_demo)``; 0 is a perfect fit, 1 explains nothing.
    n_samples : int
        Samples used, over all demonstrations.
    """

    steering: ObstacleSteering
    residual_rms: float
    relative_residual: float
    n_samples: int


def demonstrated_coupling(
    avoidance: AvoidanceDemo, model: PoseModel | None = None, params: DMPParams | None = None
) -> tuple[Array, Array, Array]:
    """Positions, velocities and the coupling acceleration a demonstration shows.

    Parameters
    ----------
    avoidance : AvoidanceDemo
    model : PoseModel, optional
        Base motion learnt without the obstacle; None is a DMP with zero forcing.
    params : DMPParams, optional
        Gains of the zero-forcing DMP when ``model`` is None.

    Returns
    -------
    positions, velocities, coupling : ndarray, shape (N, 3)
        m, m/s and m/s^2, in the demonstration's frame.
    """
    base = model if model is not None else PoseModel.still(params)
    demo = avoidance.demo
    p = base.params
    tau = avoidance.tau if avoidance.tau is not None else demo.duration
    y = demo.positions
    yd, ydd = demo.position_derivatives()
    y0, g = y[0], y[-1]
    s = np.exp(-p.alpha_s * (demo.t - demo.t[0]) / tau)
    target = base.target(y0, quat.IDENTITY, g, quat.IDENTITY, tau)
    forcing = base.position.forcing
    f = ((forcing.basis.normalised(s) * s[:, None]) @ forcing.weights) @ target.position_matrix.T
    ydd_dmp = (p.alpha * (p.beta * (g - y) - tau * yd) + f) / (tau * tau)
    return y, yd, ydd - ydd_dmp


def fit_obstacle_steering(
    demos: AvoidanceDemo | Sequence[AvoidanceDemo],
    model: PoseModel | None = None,
    params: DMPParams | None = None,
    object_radius: float = 0.0,
    max_angle: float = math.pi,
) -> SteeringFit:
    """Fit ``gamma, beta, k`` of the steering law to demonstrated avoidance.

    Parameters
    ----------
    demos : AvoidanceDemo or sequence of AvoidanceDemo
    model : PoseModel, optional
        Base motion learnt without obstacles (same start and goal); None is zero forcing.
    params : DMPParams, optional
        Gains of the zero-forcing base DMP when ``model`` is None.
    object_radius : float
        Bounding radius of the carried object, m.
    max_angle : float
        Passed to :class:`ObstacleSteering`, rad.

    Returns
    -------
    SteeringFit

    Raises
    ------
    ValueError
        If no demonstration is given or the demonstrated coupling is zero.
    """
    items = [demos] if isinstance(demos, AvoidanceDemo) else list(demos)
    if not items:
        raise ValueError("demos: expected at least one avoidance demonstration, got none")
    r_obj = non_negative(object_radius, "object_radius")
    data = []
    for item in items:  # one block per demonstration: each has its own obstacles
        y, yd, c = demonstrated_coupling(item, model, params)
        data.append((y, yd, item.centres, item.radii + r_obj, c))
    c_all = np.concatenate([d[4] for d in data]).ravel()
    c_rms = float(np.sqrt(np.mean(c_all * c_all)))
    if c_rms == 0.0:
        raise ValueError("demos: expected a demonstrated coupling, got zero (no avoidance)")

    def law(x: Array) -> Array:
        return np.concatenate(
            [
                steering_accelerations(y, yd, o, r, x[0], x[1], x[2], max_angle)
                for y, yd, o, r, _ in data
            ]
        ).ravel()

    best = (math.inf, np.array((1.0, 1.0, 0.0)))
    for beta in _BETA_GRID:
        for k in _K_GRID:
            unit = law(np.array((1.0, beta, k)))
            uu = float(unit @ unit)
            if uu == 0.0:
                continue
            gamma = max(float(unit @ c_all) / uu, 1e-6)
            cost = float(np.sum((gamma * unit - c_all) ** 2))
            if cost < best[0]:
                best = (cost, np.array((gamma, beta, k)))
    # Imported here: scipy.optimize costs about half a second to import, which every command
    # that registers the leaves (validate, nodes) would pay without fitting anything.
    from scipy.optimize import least_squares

    result = least_squares(
        lambda x: law(x) - c_all,
        best[1],
        bounds=(np.array((1e-9, 1e-9, 0.0)), np.full(3, np.inf)),
        x_scale="jac",
        method="trf",
    )
    gamma, beta, k = (float(v) for v in result.x)
    rms = float(np.sqrt(np.mean(result.fun**2)))
    steering = ObstacleSteering(
        gamma, beta, k, data[0][2], items[0].radii, object_radius=r_obj, max_angle=max_angle
    )
    return SteeringFit(steering, rms, rms / c_rms, int(c_all.size // 3))
