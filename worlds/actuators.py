"""Actuators that are not ideal torque sources: scale and bias errors, a lag and a latency.

The impedance controller (:class:`worlds.control.DualArmImpedanceController`) computes a
torque per joint at every physics step (its *tick*: :meth:`~worlds.control.
DualArmImpedanceController.apply` runs once before every ``stepSimulation``). With
:class:`ActuatorFaults` handed to it, what PyBullet receives is that torque passed through
:func:`actuator_step`, in this order:

1. latency: the torque applied over tick ``k`` is the one computed at tick
   ``k - latency_ticks``, from the joint state read at that tick (for ``k < latency_ticks``,
   the one computed at tick 0);
2. scale and bias: ``scale * torque + bias``, per joint;
3. a first-order lag of time constant ``lag_s`` (``lag_s * dy/dt = u - y``), integrated
   exactly for an input held over each tick: ``y += (1 - exp(-dt / lag_s)) * (u - y)``, the
   torque applied over the tick being ``y`` at its end, so a step in the commanded torque
   reaches ``1 - 1/e`` (63.2 %) of its size ``lag_s`` after it is first applied;
4. saturation at the joint's torque limit.

At tick 0 the actuators are taken to have held tick 0's torque for ever (the latency queue
full of it, the lag settled on it), so that switching on causes no transient of its own.

Joints are ordered as the controller stacks them: the left arm's, then the right arm's.

A robot whose joints sense their torque closes a loop around such actuators
(:class:`TorqueLoop`, :func:`torque_loop_step`): integral action on the gap between the
torque the law asked for and the torque the joint sensed, added to what is sent. It removes
a constant bias and a scale error (the gravity load held by a scaled motor) in a few of its
time constants. A proportional part on the same gap shortens the lag as the joint sees it
(63 % of a step through a 30 ms lag in 25 ms, not 42, at a gain of 0.5).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class ActuatorFaults:
    """How every joint's actuator differs from an ideal torque source.

    Attributes
    ----------
    torque_scale : tuple of float
        (m,) factor on each joint's torque, > 0.
    torque_bias_nm : tuple of float
        (m,) torque added to each joint's, N m.
    lag_s : float
        Time constant of the first-order lag on every joint's torque, s, >= 0 (0: none).
    latency_ticks : int
        Controller ticks (physics steps) between reading the joint state and applying the
        torque computed from it, >= 0.
    """

    torque_scale: tuple[float, ...]
    torque_bias_nm: tuple[float, ...]
    lag_s: float = 0.0
    latency_ticks: int = 0

    def __post_init__(self) -> None:
        name = "ActuatorFaults"
        scale = tuple(float(v) for v in self.torque_scale)
        bias = tuple(float(v) for v in self.torque_bias_nm)
        if len(scale) != len(bias) or not scale:
            raise ValueError(
                f"{name}: expected torque_scale and torque_bias_nm of one equal, non-zero "
                f"length, got {len(scale)} and {len(bias)}"
            )
        if not all(math.isfinite(v) and v > 0.0 for v in scale):
            raise ValueError(f"{name}: expected torque_scale finite and > 0, got {scale}")
        if not all(math.isfinite(v) for v in bias):
            raise ValueError(f"{name}: expected torque_bias_nm finite, got {bias}")
        if not (math.isfinite(self.lag_s) and self.lag_s >= 0.0):
            raise ValueError(f"{name}: expected lag_s finite and >= 0, got {self.lag_s}")
        if isinstance(self.latency_ticks, bool) or not isinstance(self.latency_ticks, int):
            raise ValueError(f"{name}: expected latency_ticks an int, got {self.latency_ticks!r}")
        if self.latency_ticks < 0:
            raise ValueError(f"{name}: expected latency_ticks >= 0, got {self.latency_ticks}")
        object.__setattr__(self, "torque_scale", scale)
        object.__setattr__(self, "torque_bias_nm", bias)
        object.__setattr__(self, "lag_s", float(self.lag_s))

    @property
    def joints(self) -> int:
        """Number of joints the faults describe."""
        return len(self.torque_scale)

    def summary(self) -> dict[str, Any]:
        """JSON-ready: every value, as held."""
        return {
            "torque_scale": list(self.torque_scale),
            "torque_bias_nm": list(self.torque_bias_nm),
            "lag_s": self.lag_s,
            "latency_ticks": self.latency_ticks,
        }


@dataclass(frozen=True)
class ActuatorState:
    """The actuators' memory between ticks.

    Attributes
    ----------
    queue : ndarray
        (latency_ticks, m) torques computed but not yet applied, oldest first, N m.
    lagged : ndarray
        (m,) the lag's output at the end of the last tick (before saturation), N m.
    """

    queue: FloatArray
    lagged: FloatArray


def lag_gain(lag_s: float, dt: float) -> float:
    """Fraction of the gap to its input a first-order lag closes in one tick of ``dt`` s with
    the input held over the tick: ``1 - exp(-dt / lag_s)``; 1 without a lag (``lag_s`` 0)."""
    return 1.0 if lag_s == 0.0 else -math.expm1(-dt / lag_s)


def actuator_start(commanded: ArrayLike, faults: ActuatorFaults) -> ActuatorState:
    """The actuators at tick 0, having held the ``commanded`` torques (m,) N m for ever."""
    tau = np.asarray(commanded, dtype=float).reshape(faults.joints)
    return ActuatorState(
        np.tile(tau, (faults.latency_ticks, 1)),
        np.asarray(faults.torque_scale) * tau + np.asarray(faults.torque_bias_nm),
    )


def actuator_step(
    state: ActuatorState,
    commanded: ArrayLike,
    faults: ActuatorFaults,
    gain: float,
    limit: ArrayLike,
) -> tuple[ActuatorState, FloatArray]:
    """One tick of the actuators: the torques (m,) applied over it and the state after it.

    Parameters
    ----------
    state : ActuatorState
        After the last tick (:func:`actuator_start` before the first).
    commanded : array_like
        (m,) torques the controller computed this tick, N m.
    faults : ActuatorFaults
        The actuators.
    gain : float
        :func:`lag_gain` of ``faults.lag_s`` and the tick's length.
    limit : array_like
        (m,) each joint's torque limit, N m, > 0.

    Returns
    -------
    ActuatorState
        The state after this tick.
    ndarray
        (m,) torques applied over this tick, N m, within ``+-limit``.
    """
    tau = np.asarray(commanded, dtype=float).reshape(faults.joints)
    if faults.latency_ticks:
        delayed = state.queue[0]
        queue = np.concatenate((state.queue[1:], tau[None, :]))
    else:
        delayed, queue = tau, state.queue
    target = np.asarray(faults.torque_scale) * delayed + np.asarray(faults.torque_bias_nm)
    # Without a lag the target itself, not y + (u - y), which rounds.
    lagged = target if gain == 1.0 else state.lagged + gain * (target - state.lagged)
    bound = np.asarray(limit, dtype=float)
    return ActuatorState(queue, lagged), np.minimum(np.maximum(lagged, -bound), bound)


@dataclass(frozen=True)
class TorqueLoop:
    """Integral and proportional action on each joint's torque, from its torque sensor.

    The sensed torque is the one the actuator applied over the last tick (a joint torque
    sensor between motor and link, as in every joint of the KUKA LBR iiwa; the iCub
    estimates its arms' joint torques from the force-torque sensors in its upper arms). Each
    tick, the gap ``asked - sensed`` of the last tick is low-passed (time constant
    ``filter_s``) and integrated (``integral_s``: a constant gap ``e`` adds ``e`` to what is
    sent every ``integral_s`` seconds), and the integral, within ``+-limit`` of each joint's
    torque limit, is added to what the law asks, with ``proportional`` times the gap itself.

    The proportional part feeds the gap back a tick and more late (the sensor reads the last
    tick; the actuators may add latency): with a lag-free actuator of scale ``s`` it rings
    unless ``proportional * s < 1``, and a gain of 0.5 sets the iiwa's light last joint
    (0.002 kg m^2 with its palm, damped at the edge of what 240 Hz allows) spinning. The
    iiwa has none; the iCub, whose light arms flail under a 30 ms lag without it (every
    joint, 0.1 m off its palm target), has 0.5.

    Without the filter the loop integrates the lag's own gap, ``lag * d(torque)/dt``: a gain
    of ``lag / integral_s`` more on the law's fast torques, which set the iiwa's light wrist
    oscillating (a 0.1 s integral with a 19 ms lag, Hard trial 18 of seed 0). The filter keeps
    that gain off the fast torques: at 0.2 s and 0.05 s the loop crosses over near 5 rad/s
    with a phase margin near 60 degrees for a lag of up to 30 ms and a tick of latency.

    Attributes
    ----------
    integral_s : float
        Integral time constant, s, > 0.
    filter_s : float
        Time constant of the low-pass filter on the gap, s, >= 0 (0: none).
    limit : float
        Largest integral as a fraction of each joint's torque limit, in (0, 1].
    proportional : float
        Gain on the unfiltered gap, in [0, 1).
    """

    integral_s: float = 0.2
    filter_s: float = 0.05
    limit: float = 0.25
    proportional: float = 0.0

    def __post_init__(self) -> None:
        name = "TorqueLoop"
        if not (math.isfinite(self.integral_s) and self.integral_s > 0.0):
            raise ValueError(f"{name}: expected integral_s finite and > 0, got {self.integral_s}")
        if not (math.isfinite(self.filter_s) and self.filter_s >= 0.0):
            raise ValueError(f"{name}: expected filter_s finite and >= 0, got {self.filter_s}")
        if not (math.isfinite(self.limit) and 0.0 < self.limit <= 1.0):
            raise ValueError(f"{name}: expected limit in (0, 1], got {self.limit}")
        if not (math.isfinite(self.proportional) and 0.0 <= self.proportional < 1.0):
            raise ValueError(f"{name}: expected proportional in [0, 1), got {self.proportional}")

    def summary(self) -> dict[str, Any]:
        """JSON-ready: every value."""
        return asdict(self)


@dataclass(frozen=True)
class TorqueLoopState:
    """The torque loop's memory between ticks.

    Attributes
    ----------
    asked : ndarray
        (m,) torques the law asked for at the last tick, N m.
    gap : ndarray
        (m,) the filtered gap ``asked - sensed``, N m.
    integral : ndarray
        (m,) the integral added to what is sent, N m.
    """

    asked: FloatArray
    gap: FloatArray
    integral: FloatArray


def torque_loop_start(joints: int) -> TorqueLoopState:
    """The loop before its first tick: nothing asked, nothing integrated."""
    zeros = np.zeros(joints)
    return TorqueLoopState(zeros, zeros.copy(), zeros.copy())


def torque_loop_step(
    state: TorqueLoopState,
    sensed: ArrayLike | None,
    asked: ArrayLike,
    loop: TorqueLoop,
    dt: float,
    limit: ArrayLike,
) -> tuple[TorqueLoopState, FloatArray]:
    """One tick of the torque loop: the torques (m,) to send and the state after it.

    Parameters
    ----------
    state : TorqueLoopState
        After the last tick (:func:`torque_loop_start` before the first).
    sensed : array_like, optional
        (m,) torques the joints sensed over the last tick, N m; None at the first tick.
    asked : array_like
        (m,) torques the law asks for this tick, within the limits, N m.
    loop : TorqueLoop
    dt : float
        The tick, s.
    limit : array_like
        (m,) each joint's torque limit, N m, > 0.

    Returns
    -------
    TorqueLoopState
    ndarray
        (m,) ``asked`` plus the integral and the proportional part, within ``+-limit``.
    """
    bound = np.asarray(limit, dtype=float)
    want = np.asarray(asked, dtype=float)
    gap, integral = state.gap, state.integral
    extra = integral
    if sensed is not None:
        error = state.asked - np.asarray(sensed, dtype=float)
        gap = error if loop.filter_s == 0.0 else gap + (dt / loop.filter_s) * (error - gap)
        reach = loop.limit * bound
        integral = np.minimum(np.maximum(integral + (dt / loop.integral_s) * gap, -reach), reach)
        extra = integral + loop.proportional * error  # exactly the integral at 0
    sent = np.minimum(np.maximum(want + extra, -bound), bound)
    return TorqueLoopState(want.copy(), gap, integral), sent


__all__ = [
    "ActuatorFaults",
    "ActuatorState",
    "TorqueLoop",
    "TorqueLoopState",
    "actuator_start",
    "actuator_step",
    "lag_gain",
    "torque_loop_start",
    "torque_loop_step",
]
