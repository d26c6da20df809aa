"""Workspace and joint-limit repulsion (after Gams et al. 2009)."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose

from skills import quaternion as quat
from skills.couplings import JointLimitRepulsion, WorkspaceRepulsion
from skills.couplings.limits import barrier
from skills.couplings.term import CouplingTerm
from skills.pose_dmp import PoseModel, PoseState

#: Coupling terms here ignore the DMP's target; any valid one will do.
TARGET = PoseModel.still().target(np.zeros(3), quat.IDENTITY, np.ones(3), quat.IDENTITY, 1.0)

LOWER = np.array([0.2, -0.5, 0.6])
UPPER = np.array([0.8, 0.5, 1.2])
MIDDLE = (LOWER + UPPER) / 2


def at(position: object) -> PoseState:
    return PoseState.at_rest(np.asarray(position, dtype=float))


def box(**kwargs: float) -> WorkspaceRepulsion:
    return WorkspaceRepulsion(LOWER, UPPER, **kwargs)


def test_is_a_coupling_term() -> None:
    assert isinstance(box(), CouplingTerm)


def test_zero_in_the_middle_and_anywhere_beyond_the_margin() -> None:
    ws = box(margin=0.05, gain=0.05)
    for p in (MIDDLE, LOWER + 0.0501, UPPER - 0.0501):
        lin, ang = ws.acceleration(at(p), TARGET)
        assert_allclose(lin, 0.0, atol=0.0)
        assert_allclose(ang, 0.0, atol=0.0)


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_pushes_inward_near_each_face_by_the_documented_amount(axis: int) -> None:
    ws = box(margin=0.05, gain=0.05)
    d = 0.02
    expected = 0.05 * (1 / d - 1 / 0.05)
    near_lower = MIDDLE.copy()
    near_lower[axis] = LOWER[axis] + d
    near_upper = MIDDLE.copy()
    near_upper[axis] = UPPER[axis] - d
    up, _ = ws.acceleration(at(near_lower), TARGET)
    down, _ = ws.acceleration(at(near_upper), TARGET)
    assert_allclose(up, np.eye(3)[axis] * expected, rtol=1e-12)
    assert_allclose(down, -up, rtol=1e-12)  # symmetric


def test_finite_and_strongest_at_and_beyond_the_face() -> None:
    ws = box(margin=0.05, gain=0.05, min_distance=0.001)
    at_face, _ = ws.acceleration(at([LOWER[0], MIDDLE[1], MIDDLE[2]]), TARGET)
    outside, _ = ws.acceleration(at([LOWER[0] - 0.1, MIDDLE[1], MIDDLE[2]]), TARGET)
    assert_allclose(at_face, [0.05 * (1 / 0.001 - 1 / 0.05), 0, 0], rtol=1e-12)
    assert_allclose(outside, at_face)


def test_barrier_is_continuous_at_the_margin() -> None:
    m = np.array([0.05])
    inside = barrier(np.array([0.05 - 1e-9]), np.array([1.0]), 0.05, m, m / 100)
    assert_allclose(inside, 0.0, atol=1e-7)


def test_joint_limits_push_each_joint_inward_through_the_jacobian() -> None:
    lower = np.full(6, -2.0)
    upper = np.full(6, 2.0)
    q = np.zeros(6)
    jac = np.eye(6)
    rep = JointLimitRepulsion(lambda: q, lambda: jac, lower, upper, margin=0.2, gain=0.1)
    lin, ang = rep.acceleration(at(MIDDLE), TARGET)
    assert_allclose(np.concatenate((lin, ang)), 0.0, atol=0.0)  # middle
    expected = 0.1 * (1 / 0.1 - 1 / 0.2)
    for j in range(6):
        q[:] = 0.0
        q[j] = 1.9  # 0.1 rad from the upper limit
        lin, ang = rep.acceleration(at(MIDDLE), TARGET)
        assert_allclose(np.concatenate((lin, ang)), -np.eye(6)[j] * expected, rtol=1e-12)
        q[j] = -1.9
        lin, ang = rep.acceleration(at(MIDDLE), TARGET)
        assert_allclose(np.concatenate((lin, ang)), np.eye(6)[j] * expected, rtol=1e-12)


def test_joint_repulsion_maps_through_a_general_jacobian() -> None:
    rng = np.random.default_rng(2)
    jac = rng.normal(size=(6, 7))
    q = np.array([0.0, 1.95, 0.0, -1.9, 0.0, 0.0, 0.0])
    rep = JointLimitRepulsion(lambda: q, lambda: jac, np.full(7, -2.0), np.full(7, 2.0))
    qdd = rep.joint_acceleration()
    assert qdd[1] < 0.0 and qdd[3] > 0.0
    assert_allclose(qdd[[0, 2, 4, 5, 6]], 0.0)
    lin, ang = rep.acceleration(at(MIDDLE), TARGET)
    assert_allclose(np.concatenate((lin, ang)), jac @ qdd, rtol=1e-12)


def test_bad_parameters_name_the_field() -> None:
    with pytest.raises(ValueError, match=r"upper: expected upper > lower, got upper\[1\]"):
        WorkspaceRepulsion(LOWER, [0.8, -0.6, 1.2])
    with pytest.raises(ValueError, match="margin"):
        box(margin=0.0)
    with pytest.raises(ValueError, match="gain"):
        box(gain=-1.0)
    with pytest.raises(ValueError, match="min_distance"):
        box(margin=0.05, min_distance=0.1)
    with pytest.raises(ValueError, match="lower: expected shape"):
        WorkspaceRepulsion([0, 0], [1, 1])
    rep = JointLimitRepulsion(lambda: np.zeros(3), lambda: np.eye(6, 7), [-1] * 7, [1] * 7)
    with pytest.raises(ValueError, match=r"joint_positions: expected shape \(7,\)"):
        rep.acceleration(at(MIDDLE), TARGET)
    bad_jac = JointLimitRepulsion(lambda: np.full(2, 0.95), lambda: np.eye(3), [-1, -1], [1, 1])
    with pytest.raises(ValueError, match=r"jacobian: expected shape \(6, 2\)"):
        bad_jac.acceleration(at(MIDDLE), TARGET)
