"""A learnt pose DMP: three positional DMPs and one quaternion DMP sharing one phase.

This is the unit the paper composes: an absolute skill moves the object's pose, a relative
skill moves a palm's pose in the object frame. :func:`fit_pose` learns one from
demonstrations (one ridge solve for all six dimensions); :meth:`PoseModel.target` binds it to
a start, a goal and a duration.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike

from skills import quaternion as quat
from skills.demonstration import Demonstration
from skills.dmp import (
    DMPParams,
    ForcingTerm,
    PositionModel,
    check_demonstrations,
    design_matrix,
    normalised_position_targets,
    ridge,
)
from skills.quaternion_dmp import (
    OrientationModel,
    normalised_orientation_targets,
    orientation_reference,
)
from skills.scaling import Scaling
from skills.state import PoseTarget
from skills.types import Array


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


#: Farthest a demonstrated position may be from the origin, m (a workspace, not an orbit).
MAX_POSITION_M = 100.0
#: Shortest and longest demonstration learnt, s: below a millisecond tau^2 vanishes in every
#: acceleration; an hour is far beyond any manipulation.
DURATION_RANGE_S = (1e-3, 3600.0)
#: Least motion a demonstration must show to be learnt: a translation (m) or a rotation (rad).
MIN_MOTION = (1e-3, 1e-2)


def check_pose_demonstration(demo: Demonstration) -> None:
    """Raise ValueError unless ``demo`` is a motion a pose DMP can learn.

    Its positions within :data:`MAX_POSITION_M` of the origin, its duration within
    :data:`DURATION_RANGE_S`, and some motion: a translation or a rotation at least
    :data:`MIN_MOTION` (a motionless recording has no shape to learn).
    """
    far = float(np.max(np.abs(demo.positions)))
    if far > MAX_POSITION_M:
        raise ValueError(
            f"{demo.name}: positions: expected within {MAX_POSITION_M:g} m of the origin, "
            f"got {far:.3g} m"
        )
    low, high = DURATION_RANGE_S
    if not low <= demo.duration <= high:
        raise ValueError(
            f"{demo.name}: t: expected a duration from {low:g} s to {high:g} s, "
            f"got {demo.duration:.3g} s"
        )
    travel = float(np.max(np.ptp(demo.positions, axis=0)))
    assert demo.orientations is not None
    turn = float(np.max(quat.angle_between(demo.orientations[0], demo.orientations)))
    if travel < MIN_MOTION[0] and turn < MIN_MOTION[1]:
        raise ValueError(
            f"{demo.name}: expected a motion (a translation of at least {MIN_MOTION[0]:g} m "
            f"or a rotation of at least {MIN_MOTION[1]:g} rad), got {travel:.3g} m and "
            f"{turn:.3g} rad: the demonstration does not move"
        )
    # Along the recorded path (signs made continuous), no sample may be half a turn or more
    # from the start or from the goal: a unit-quaternion DMP's goal error, 2 log(g q^-1), takes
    # the short way round, so a demonstrated 270 deg turn is learnt as -90 deg and, sent to
    # other goals, turned the long way (545 deg for a goal of 185 deg).
    q = quat.make_continuous(demo.orientations)
    half_turn = min(float(np.min(q @ q[0])), float(np.min(q @ q[-1])))
    if half_turn < 0.0:
        widest = np.degrees(2.0 * np.arccos(np.clip(half_turn, -1.0, 1.0)))
        raise ValueError(
            f"{demo.name}: orientations: expected a turn of under 180 deg between any sample "
            f"and the start or the goal (a quaternion DMP's goal error takes the short way "
            f"round), got one turning {widest:.0f} deg: record it as two skills of under 180 deg "
            "each"
        )


#: :func:`fit_pose`'s reference changes below which an axis does not scale, m and rad.
MIN_AMPLITUDE_M = 1e-3
MIN_ROTATION_RAD = 1e-2


def fit_pose(
    demos: Demonstration | Sequence[Demonstration],
    params: DMPParams | None = None,
    position_scaling: Scaling = Scaling.AMPLITUDE,
    orientation_scaling: Scaling = Scaling.AMPLITUDE,
    min_amplitude: float = MIN_AMPLITUDE_M,
    min_rotation: float = MIN_ROTATION_RAD,
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
        If a demonstration has no orientations, its positions are not 3-D, or it is not a
        motion to learn (:func:`check_pose_demonstration`).
    """
    demo_list = [demos] if isinstance(demos, Demonstration) else list(demos)
    for d in demo_list:
        if d.positions.shape[1] != 3:
            raise ValueError(f"{d.name}: positions: expected shape (N, 3), got {d.positions.shape}")
        if d.orientations is None:
            raise ValueError(f"{d.name}: orientations: expected (N, 4) quaternions, got none")
        check_pose_demonstration(d)
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
