"""Grasp maintenance in the relative space (Gams et al. 2014).

The DMP these terms couple to moves one palm's pose in the object frame {O}. The grasp
geometry gives that palm a contact pose in {O}; the terms are virtual spring-dampers (per unit
mass) towards it, so the palm keeps its place on the object while absolute skills move the
object.

* :class:`GraspMaintenance`: the position reference is the contact point pushed
  ``squeeze_depth`` along the inward normal (into the object), so at rest against the face the
  spring keeps pressing: ``K (p_ref + depth n - p) - D v`` and
  ``K_rot rotation_error(q_ref, q) - D_rot omega``.
* :class:`ForceTrackingGrasp`: the same tangential and rotational springs, but along the
  normal it tracks a contact force: ``K_f (F_des - F_meas) n - D (v . n) n``.

The inward normal defaults to the direction from the contact point to the object's origin
(right for contacts at face centres of a box or any centred convex object).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from skills import quaternion as quat
from skills.couplings._checks import assign, non_negative, positive, unit_vector, vector
from skills.kernel import kernel, quaternion_at, rotation_error_q
from skills.program import Kind, Packer
from skills.state import PoseState, PoseTarget
from skills.types import Array


def _inward(position: Array, normal: ArrayLike | None) -> Array:
    if normal is not None:
        return unit_vector(normal, "inward_normal_object")
    if float(np.linalg.norm(position)) < 1e-9:
        raise ValueError(
            "inward_normal_object: expected a normal when the contact is at the object's origin"
        )
    return unit_vector(-position, "inward_normal_object")


def _no_force() -> float:
    return 0.0


def _damping(damping: float | None, stiffness: float, name: str) -> float:
    # Critical damping of a unit mass: D = 2 sqrt(K).
    return 2.0 * math.sqrt(stiffness) if damping is None else non_negative(damping, name)


@dataclass(frozen=True, eq=False, init=False)
class GraspMaintenance:
    """Spring-damper holding a palm at its contact pose in {O}, squeezing (a coupling term).

    Parameters
    ----------
    contact_position_object : array_like, shape (3,)
        Contact point of the palm in {O}, m (on the object's surface).
    contact_orientation_object : array_like, shape (4,)
        Palm orientation at contact in {O}, ``(x, y, z, w)``.
    squeeze_depth : float
        How far past the surface the reference sits, m (>= 0).
    stiffness : float
        ``K``, 1/s^2 (> 0).
    damping : float or None
        ``D``, 1/s (>= 0); None is critical, ``2 sqrt(K)``.
    rotational_stiffness : float
        ``K_rot``, 1/s^2 (> 0).
    rotational_damping : float or None
        ``D_rot``, 1/s; None is critical.
    inward_normal_object : array_like, shape (3,), optional
        Unit direction into the object at the contact, {O}; default towards {O}'s origin.
    """

    contact_position_object: Array
    contact_orientation_object: Array
    squeeze_depth: float
    stiffness: float
    damping: float | None
    rotational_stiffness: float
    rotational_damping: float | None
    inward_normal_object: Array | None
    _ref: tuple[float, ...] = field(init=False, repr=False)

    def __init__(
        self,
        contact_position_object: ArrayLike,
        contact_orientation_object: ArrayLike,
        squeeze_depth: float = 0.01,
        stiffness: float = 400.0,
        damping: float | None = None,
        rotational_stiffness: float = 200.0,
        rotational_damping: float | None = None,
        inward_normal_object: ArrayLike | None = None,
    ) -> None:
        assign(
            self,
            contact_position_object=contact_position_object,
            contact_orientation_object=contact_orientation_object,
            squeeze_depth=squeeze_depth,
            stiffness=stiffness,
            damping=damping,
            rotational_stiffness=rotational_stiffness,
            rotational_damping=rotational_damping,
            inward_normal_object=inward_normal_object,
        )
        self.__post_init__()

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        p = vector(self.contact_position_object, (3,), "contact_position_object")
        q = quat.as_quaternions(self.contact_orientation_object, "contact_orientation_object")
        if q.shape != (4,):
            raise ValueError(f"contact_orientation_object: expected shape (4,), got {q.shape}")
        n = _inward(p, self.inward_normal_object)
        depth = non_negative(self.squeeze_depth, "squeeze_depth")
        k = positive(self.stiffness, "stiffness")
        k_rot = positive(self.rotational_stiffness, "rotational_stiffness")
        set_(self, "contact_position_object", p)
        set_(self, "contact_orientation_object", q)
        set_(self, "inward_normal_object", n)
        set_(self, "squeeze_depth", depth)
        set_(self, "stiffness", k)
        set_(self, "rotational_stiffness", k_rot)
        set_(self, "damping", _damping(self.damping, k, "damping"))
        set_(
            self,
            "rotational_damping",
            _damping(self.rotational_damping, k_rot, "rotational_damping"),
        )
        set_(self, "_ref", (*(p + depth * n).tolist(), *q.tolist()))

    @property
    def reference_position_object(self) -> Array:
        """The squeezed position reference in {O}, m, shape (3,)."""
        return np.array(self._ref[:3])

    def acceleration(self, state: PoseState, target: PoseTarget) -> tuple[Array, Array]:
        """Spring-damper accelerations of the palm in {O}.

        Parameters
        ----------
        state : PoseState
            The palm's pose and twist in {O}.
        target : PoseTarget
            Unused.

        Returns
        -------
        linear : ndarray, shape (3,)
            m/s^2, {O}.
        angular : ndarray, shape (3,)
            rad/s^2, {O}.
        """
        p_ref = np.array(self._ref[:3])
        q_ref = np.array(self._ref[3:])
        assert self.damping is not None and self.rotational_damping is not None
        return (
            self.stiffness * (p_ref - state.position) - self.damping * state.velocity,
            self.rotational_stiffness * quat.rotation_error(q_ref, state.orientation)
            - self.rotational_damping * state.angular_velocity,
        )

    def pack(self, packer: Packer, weight: float) -> None:
        """A GRASP block: ``[w, reference xyz, reference xyzw, K, D, K_rot, D_rot]``."""
        packer.add(
            Kind.GRASP,
            [
                weight,
                *self._ref,
                self.stiffness,
                float(self.damping or 0.0),
                self.rotational_stiffness,
                float(self.rotational_damping or 0.0),
            ],
        )


@kernel
def grasp_kernel(x: Array, b: int, data: Array, o: int, a: Array) -> None:
    """:meth:`GraspMaintenance.acceleration` of the palm state at ``x[b:]`` from its block at
    ``data[o:]``, into ``a`` (6)."""
    e = rotation_error_q(quaternion_at(data, o + 4), quaternion_at(x, b + 9))
    k, d, kr, dr = data[o + 8], data[o + 9], data[o + 10], data[o + 11]
    for i in range(3):
        a[i] = k * (data[o + 1 + i] - x[b + i]) - d * x[b + 3 + i]
        a[3 + i] = kr * e[i] - dr * x[b + 13 + i]


@dataclass(frozen=True, eq=False, init=False)
class ForceTrackingGrasp:
    """Holds a palm at its contact pose tangentially and tracks a normal force (a coupling term).

    Along the inward normal ``n``: ``K_f (F_des - F_meas) - D (v . n)``; across it and in
    rotation, the springs of :class:`GraspMaintenance` towards the contact pose (no squeeze).

    Parameters
    ----------
    contact_position_object, contact_orientation_object, inward_normal_object
        As :class:`GraspMaintenance`.
    desired_force : float
        ``F_des``, N, compression positive (>= 0).
    force_gain : float
        ``K_f``, m/s^2 per N (> 0).
    measured_force : callable
        ``() -> float``: the current normal contact force, N; read once per tick. Use
        :meth:`with_measured_force` to set a value instead.
    stiffness, damping, rotational_stiffness, rotational_damping
        As :class:`GraspMaintenance`; ``damping`` also damps the normal motion.
    """

    contact_position_object: Array
    contact_orientation_object: Array
    desired_force: float
    force_gain: float
    measured_force: Callable[[], float]
    stiffness: float
    damping: float | None
    rotational_stiffness: float
    rotational_damping: float | None
    inward_normal_object: Array | None
    _spring: GraspMaintenance = field(init=False, repr=False)

    def __init__(
        self,
        contact_position_object: ArrayLike,
        contact_orientation_object: ArrayLike,
        desired_force: float,
        force_gain: float = 0.05,
        measured_force: Callable[[], float] = _no_force,
        stiffness: float = 400.0,
        damping: float | None = None,
        rotational_stiffness: float = 200.0,
        rotational_damping: float | None = None,
        inward_normal_object: ArrayLike | None = None,
    ) -> None:
        assign(
            self,
            contact_position_object=contact_position_object,
            contact_orientation_object=contact_orientation_object,
            desired_force=desired_force,
            force_gain=force_gain,
            measured_force=measured_force,
            stiffness=stiffness,
            damping=damping,
            rotational_stiffness=rotational_stiffness,
            rotational_damping=rotational_damping,
            inward_normal_object=inward_normal_object,
        )
        self.__post_init__()

    def __post_init__(self) -> None:
        spring = GraspMaintenance(
            self.contact_position_object,
            self.contact_orientation_object,
            0.0,
            self.stiffness,
            self.damping,
            self.rotational_stiffness,
            self.rotational_damping,
            self.inward_normal_object,
        )
        set_ = object.__setattr__
        for name in (
            "contact_position_object",
            "contact_orientation_object",
            "inward_normal_object",
            "stiffness",
            "damping",
            "rotational_stiffness",
            "rotational_damping",
        ):
            set_(self, name, getattr(spring, name))
        set_(self, "desired_force", non_negative(self.desired_force, "desired_force"))
        set_(self, "force_gain", positive(self.force_gain, "force_gain"))
        if not callable(self.measured_force):
            raise ValueError(
                f"measured_force: expected a callable () -> float, got {self.measured_force!r}"
            )
        set_(self, "_spring", spring)

    def with_measured_force(self, force: float) -> ForceTrackingGrasp:
        """A copy reading a fixed measured normal force, N (cheap: no re-validation)."""
        value = float(force)
        if not math.isfinite(value):
            raise ValueError(f"force: expected a finite force in N, got {force!r}")
        out = object.__new__(ForceTrackingGrasp)
        out.__dict__.update(self.__dict__)
        object.__setattr__(out, "measured_force", lambda: value)
        return out

    def acceleration(self, state: PoseState, target: PoseTarget) -> tuple[Array, Array]:
        """Accelerations of the palm in {O}: linear m/s^2, angular rad/s^2, (3,) each."""
        lin, ang = self._spring.acceleration(state, target)
        n = self.inward_normal_object
        assert n is not None  # set in __post_init__
        # Replace the spring's normal component by force tracking plus normal damping.
        d = self.damping
        assert d is not None
        along = self.force_gain * (self.desired_force - float(self.measured_force())) - d * float(
            state.velocity @ n
        )
        lin += (along - float(lin @ n)) * n
        return lin, ang
