"""Grasp maintenance in the object frame (Gams et al. 2014): spring and force tracking."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from skills import quaternion as quat
from skills.couplings import ForceTrackingGrasp, GraspMaintenance
from skills.couplings.term import CouplingTerm
from skills.interpreter import kernel_acceleration
from skills.pose_dmp import PoseModel, PoseState

#: Coupling terms here ignore the DMP's target; any valid one will do.
TARGET = PoseModel.still().target(np.zeros(3), quat.IDENTITY, np.ones(3), quat.IDENTITY, 1.0)

# Left palm on the -y face of a 0.2 x 0.3 x 0.15 m parcel, palm z pointing into the object.
CONTACT = np.array([0.0, -0.15, 0.0])
PALM = quat.from_axis_angle(np.array([1.0, 0.0, 0.0]), -math.pi / 2)


def palm(
    position: object,
    velocity: object = (0, 0, 0),
    orientation: object = PALM,
    omega: object = (0, 0, 0),
) -> PoseState:
    z = np.zeros(3)
    return PoseState(
        np.asarray(position, dtype=float),
        np.asarray(velocity, dtype=float),
        z,
        np.asarray(orientation, dtype=float),
        np.asarray(omega, dtype=float),
        z,
    )


def test_is_a_coupling_term() -> None:
    assert isinstance(GraspMaintenance(CONTACT, PALM), CouplingTerm)
    assert isinstance(ForceTrackingGrasp(CONTACT, PALM, 15.0), CouplingTerm)


def test_equilibrium_is_exactly_at_the_squeezed_reference() -> None:
    grasp = GraspMaintenance(CONTACT, PALM, squeeze_depth=0.015)
    ref = CONTACT + np.array([0.0, 0.015, 0.0])  # inward: towards the object's origin
    assert_allclose(grasp.reference_position_object, ref)
    lin, ang = grasp.acceleration(palm(ref), TARGET)
    assert_allclose(lin, 0.0, atol=1e-15)
    assert_allclose(ang, 0.0, atol=1e-15)
    # On the surface, it keeps pressing inward with K * depth.
    lin, _ = grasp.acceleration(palm(CONTACT), TARGET)
    assert_allclose(lin, [0.0, 400.0 * 0.015, 0.0], rtol=1e-12)


def test_spring_damper_gains_and_critical_damping_default() -> None:
    grasp = GraspMaintenance(CONTACT, PALM, 0.0, stiffness=100.0, rotational_stiffness=25.0)
    assert grasp.damping == pytest.approx(20.0)
    assert grasp.rotational_damping == pytest.approx(10.0)
    tilted = quat.multiply(quat.from_axis_angle(np.array([0.0, 0.0, 1.0]), 0.1), PALM)
    lin, ang = grasp.acceleration(
        palm(CONTACT + [0.01, 0, 0], [0.0, 0.0, 0.2], tilted, [0.0, 0.0, 0.5]), TARGET
    )
    assert_allclose(lin, [-100.0 * 0.01, 0.0, -20.0 * 0.2], rtol=1e-12)
    assert_allclose(ang, [0.0, 0.0, -25.0 * 0.1 - 10.0 * 0.5], rtol=1e-9, atol=1e-12)


def test_explicit_normal_overrides_the_default() -> None:
    grasp = GraspMaintenance(CONTACT, PALM, 0.01, inward_normal_object=[0.0, 0.0, 2.0])
    assert_allclose(grasp.reference_position_object, CONTACT + [0.0, 0.0, 0.01])


def test_force_tracking_pushes_in_when_low_out_when_high_and_not_at_the_target() -> None:
    grasp = ForceTrackingGrasp(CONTACT, PALM, desired_force=15.0, force_gain=0.1)
    at_contact = palm(CONTACT)
    inward = np.array([0.0, 1.0, 0.0])
    low, _ = grasp.with_measured_force(5.0).acceleration(at_contact, TARGET)
    high, _ = grasp.with_measured_force(25.0).acceleration(at_contact, TARGET)
    exact, ang = grasp.with_measured_force(15.0).acceleration(at_contact, TARGET)
    assert_allclose(low, inward * 0.1 * 10.0, rtol=1e-12)
    assert_allclose(high, -inward * 0.1 * 10.0, rtol=1e-12)
    assert_allclose(exact, 0.0, atol=1e-15)
    assert_allclose(ang, 0.0, atol=1e-15)
    # Wherever the palm sits along the normal, only the force error acts there.
    deeper, _ = grasp.with_measured_force(15.0).acceleration(palm(CONTACT + 0.01 * inward), TARGET)
    assert_allclose(deeper, 0.0, atol=1e-15)


def test_force_tracking_keeps_the_tangential_spring_and_reads_a_sensor() -> None:
    readings = iter([15.0, 10.0])
    grasp = ForceTrackingGrasp(CONTACT, PALM, 15.0, 0.1, measured_force=lambda: next(readings))
    lin, _ = grasp.acceleration(palm(CONTACT + [0.02, 0.0, 0.0]), TARGET)
    assert_allclose(lin, [-400.0 * 0.02, 0.0, 0.0], rtol=1e-12)
    lin, _ = grasp.acceleration(palm(CONTACT), TARGET)
    assert_allclose(lin, [0.0, 0.5, 0.0], rtol=1e-12)


def test_scalar_path_matches_the_spring_damper_in_arrays() -> None:
    rng = np.random.default_rng(3)
    grasp = GraspMaintenance(CONTACT, PALM, 0.015, stiffness=300.0, rotational_stiffness=150.0)
    ref_p, ref_q = grasp.reference_position_object, grasp.contact_orientation_object
    for _ in range(20):
        s = palm(
            CONTACT + rng.normal(size=3) * 0.02,
            rng.normal(size=3) * 0.1,
            quat.as_quaternions(rng.normal(size=4)),
            rng.normal(size=3),
        )
        expected_lin = 300.0 * (ref_p - s.position) - grasp.damping * s.velocity
        expected_ang = 150.0 * quat.rotation_error(
            ref_q, s.orientation
        ) - grasp.rotational_damping * np.asarray(s.angular_velocity)
        lin, ang = grasp.acceleration(s, TARGET)
        assert_allclose([*lin, *ang], [*expected_lin, *expected_ang], rtol=1e-12, atol=1e-12)
        k_lin, k_ang = kernel_acceleration(grasp, s, TARGET)
        assert_allclose([*k_lin, *k_ang], [*lin, *ang], rtol=1e-12, atol=1e-12)


def test_bad_parameters_name_the_field() -> None:
    with pytest.raises(ValueError, match="stiffness"):
        GraspMaintenance(CONTACT, PALM, stiffness=0.0)
    with pytest.raises(ValueError, match="squeeze_depth"):
        GraspMaintenance(CONTACT, PALM, squeeze_depth=-0.01)
    with pytest.raises(ValueError, match="rotational_damping"):
        GraspMaintenance(CONTACT, PALM, rotational_damping=-1.0)
    with pytest.raises(ValueError, match="contact_orientation_object"):
        GraspMaintenance(CONTACT, [0, 0, 0, 0])
    with pytest.raises(ValueError, match="inward_normal_object"):
        GraspMaintenance([0, 0, 0], PALM)
    with pytest.raises(ValueError, match="desired_force"):
        ForceTrackingGrasp(CONTACT, PALM, -1.0)
    with pytest.raises(ValueError, match="force_gain"):
        ForceTrackingGrasp(CONTACT, PALM, 1.0, force_gain=0.0)
    with pytest.raises(ValueError, match="force: expected a finite"):
        ForceTrackingGrasp(CONTACT, PALM, 1.0).with_measured_force(math.nan)
