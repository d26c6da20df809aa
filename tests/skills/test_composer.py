"""Simultaneous composition: rigidity under absolute skills, a still object under relative ones."""

from __future__ import annotations

import numpy as np
from numpy.testing import assert_allclose

from skills import quaternion as quat
from skills.composer import (
    DualArmComposer,
    DualArmState,
    PalmCommands,
    commands_for,
    grasped_state,
    relative_from_world,
)
from skills.couplings import (
    LearntForcing,
)
from skills.couplings.term import Weighted
from skills.dual_arm import GraspGeometry, grasp_matrix
from skills.pose_dmp import PoseState, PoseTarget, coupled_step, fit_pose, pose_step
from skills.vocabulary import ARMS, Arm
from tests.skills.conftest import pick_place_demo

DT = 1.0 / 60.0


class Push:
    """A constant acceleration: the simplest coupling term."""

    def __init__(self, lin: list[float], ang: list[float]) -> None:
        self.lin, self.ang = np.array(lin), np.array(ang)

    def acceleration(self, state: PoseState, target: PoseTarget) -> tuple[np.ndarray, np.ndarray]:
        return self.lin, self.ang


def start_state() -> DualArmState:
    g = GraspGeometry.lateral(0.30)
    return grasped_state(
        [0.55, 0.0, 0.675],
        quat.IDENTITY,
        (g.left_position, g.left_orientation),
        (g.right_position, g.right_orientation),
    )


def test_absolute_skills_alone_keep_the_palms_rigid() -> None:
    pick = fit_pose(pick_place_demo())
    composer = DualArmComposer.start(
        start_state(),
        [0.65, -0.15, 0.675],
        quat.from_axis_angle([0, 0, 1], 0.6),
        tau=2.0,
        absolute=[(LearntForcing(pick), 1.0), (Push([0.0, 0.05, 0.0], [0, 0, 0.1]), 0.5)],
    )
    first = composer.commands()
    d0 = np.linalg.norm(first.positions[0] - first.positions[1])
    rel0 = quat.multiply(quat.conjugate(first.orientations[0]), first.orientations[1])
    for _ in range(int(3 * 2.0 / DT)):
        prev = composer.state.object
        cmd = composer.step(DT)
        assert abs(np.linalg.norm(cmd.positions[0] - cmd.positions[1]) - d0) < 1e-9
        rel = quat.multiply(quat.conjugate(cmd.orientations[0]), cmd.orientations[1])
        assert quat.angle_between(rel, rel0) < 1e-9
        # Each palm's twist is the object's rigid-body twist at that palm.
        r = cmd.positions - composer.state.object.position
        w = composer.state.object.angular_velocity
        assert_allclose(
            cmd.twists[:, :3], composer.state.object.velocity + np.cross(w, r), atol=1e-12
        )
        assert prev is not composer.state.object
    assert np.linalg.norm(composer.state.object.position - [0.65, -0.15, 0.675]) < 0.02


def test_relative_skills_alone_leave_the_object_still() -> None:
    state = start_state()
    composer = DualArmComposer.start(
        state,
        state.object.position,
        state.object.orientation,
        tau=2.0,
        relative={
            Arm.LEFT: [(Push([0, -0.01, 0], [0, 0, 0]), 1.0)],
            Arm.RIGHT: [(Push([0, 0.01, 0], [0, 0, 0]), 1.0)],
        },
    )
    for _ in range(120):
        cmd = composer.step(DT)
    assert_allclose(composer.state.object.position, state.object.position, atol=0)
    assert_allclose(composer.state.object.orientation, state.object.orientation, atol=0)
    assert_allclose(cmd.object_twist, np.zeros(6), atol=0)
    # The palms closed on the object: each moved inwards along y in {O}.
    assert composer.state.left.position[1] < state.left.position[1] - 0.01
    assert composer.state.right.position[1] > state.right.position[1] + 0.01


def test_relative_from_world_inverts_palm_poses() -> None:
    obj_p, obj_q = np.array([0.6, 0.1, 0.7]), quat.from_axis_angle([0.3, 0.1, 1.0], 0.8)
    rel_p, rel_q = np.array([0.0, 0.15, 0.01]), quat.from_axis_angle([1.0, 0, 0], 0.2)
    world_p = obj_p + quat.rotate(obj_q, rel_p)
    world_q = quat.multiply(obj_q, rel_q)
    back_p, back_q = relative_from_world(obj_p, obj_q, world_p, world_q)
    assert_allclose(back_p, rel_p, atol=1e-12)
    assert quat.angle_between(back_q, rel_q) < 1e-12


def perturbed(pose: PoseState, rng: np.random.Generator) -> PoseState:
    """A measured state near ``pose``: other pose and twist, same phase."""
    return PoseState(
        pose.position + rng.normal(size=3) * 0.01,
        pose.velocity + rng.normal(size=3) * 0.05,
        pose.acceleration,
        quat.as_quaternions(pose.orientation + rng.normal(size=4) * 0.05),
        pose.angular_velocity + rng.normal(size=3) * 0.1,
        pose.angular_acceleration,
        pose.phase,
    )


def general_step(composer: DualArmComposer, measured: DualArmState) -> DualArmState:
    """The step the composer's floats must equal: each space by the general pose steps."""
    alpha_s = composer.base.params.alpha_s
    obj = pose_step(measured.object, composer.base, composer.target, DT, composer.absolute)
    left, right = (
        coupled_step(
            measured.relative(arm),
            composer.relative_targets[arm],
            DT,
            composer.relative[arm],
            alpha_s,
        )
        for arm in ARMS
    )
    return DualArmState(obj, left, right)


def test_commands_are_the_palm_poses_and_eq5_twists() -> None:
    rng = np.random.default_rng(9)
    g = GraspGeometry.lateral(0.30)
    state = grasped_state(
        [0.6, 0.1, 0.7],
        quat.as_quaternions(rng.normal(size=4)),
        (g.left_position, g.left_orientation),
        (g.right_position, g.right_orientation),
    )
    state = DualArmState(*(perturbed(s, rng) for s in (state.object, state.left, state.right)))
    cmd: PalmCommands = commands_for(state)
    obj, palms = state.object, (state.left, state.right)
    to_world = quat.to_matrix(obj.orientation)
    levers = np.stack([to_world @ p.position for p in palms])
    positions = obj.position + levers
    orientations = np.stack([quat.multiply(obj.orientation, p.orientation) for p in palms])
    # G^T [v; w] is each contact's rigid-body twist; each palm adds its own motion in {O}.
    rigid = (grasp_matrix(levers).T @ obj.twist()).reshape(2, 6)
    own = np.stack(
        [np.concatenate((to_world @ p.velocity, to_world @ p.angular_velocity)) for p in palms]
    )
    twists = rigid + own
    assert_allclose(cmd.positions, positions, atol=1e-12)
    assert_allclose(cmd.orientations, orientations, atol=1e-12)
    assert_allclose(cmd.twists, twists, atol=1e-12)
    assert_allclose(cmd.object_twist, obj.twist(), atol=0)


def test_reassigned_terms_take_effect_at_the_next_step() -> None:
    composer = DualArmComposer.start(
        start_state(), [0.65, 0.0, 0.675], quat.IDENTITY, 2.0, [(Push([0, 0, 0.1], [0, 0, 0]), 1.0)]
    )
    composer.step(DT)
    composer.absolute = (Weighted(Push([0.0, 0.3, 0.0], [0.0, 0.0, 0.2]), 1.0),)
    measured = composer.state
    composer.step(DT, measured)
    expected = general_step(composer, measured)
    assert_allclose(composer.state.object.acceleration, expected.object.acceleration, atol=1e-12)
    assert_allclose(
        composer.state.object.angular_acceleration,
        expected.object.angular_acceleration,
        atol=1e-12,
    )
