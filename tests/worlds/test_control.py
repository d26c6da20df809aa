"""Impedance control: the pure law, palm tracking in PyBullet, the scene."""

from __future__ import annotations

import numpy as np
import pybullet as pb
import pytest
from scipy.spatial.transform import Rotation

from skills import quaternion as quat
from skills.vocabulary import Arm
from worlds.impedance import AffineTorqueLaw, affine_law, impedance_terms
from worlds.impedance_values import GainArrays, ImpedanceGains, PalmCommand
from worlds.palm_poses import LATERAL_PALM_QUATERNIONS
from worlds.robots import build_robot_model
from worlds.scene import Scene
from worlds.spec import SceneSpec

RNG_SEED = 3


# -- values ---------------------------------------------------------------------------------


def test_palm_command_validates_and_normalises() -> None:
    command = PalmCommand(np.zeros(3), np.array([0.0, 0.0, 0.0, 2.0]))
    np.testing.assert_allclose(command.quaternion, [0, 0, 0, 1])
    with pytest.raises(ValueError, match=r"PalmCommand.position: expected shape \(3,\)"):
        PalmCommand(np.zeros(4), np.array([0.0, 0.0, 0.0, 1.0]))
    with pytest.raises(ValueError, match="expected a unit quaternion"):
        PalmCommand(np.zeros(3), np.zeros(4))
    with pytest.raises(ValueError, match="expected finite"):
        PalmCommand(np.array([0.0, np.nan, 0.0]), np.array([0.0, 0.0, 0.0, 1.0]))


def test_squeeze_offset_moves_the_target_along_the_palm_normal() -> None:
    quaternion = np.array(LATERAL_PALM_QUATERNIONS[Arm.LEFT])
    command = PalmCommand(np.array([0.6, 0.16, 0.7]), quaternion, squeeze_offset=0.015)
    # The left palm's normal points along -y, into the object's +y face.
    np.testing.assert_allclose(command.target_position(), [0.6, 0.145, 0.7], atol=1e-12)


def test_gains_reject_negative_values() -> None:
    with pytest.raises(ValueError, match="stiffness_linear: expected finite >= 0"):
        ImpedanceGains(stiffness_linear=-1.0)


# -- the pure law ---------------------------------------------------------------------------


def _random_law_inputs(seed: int) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    n = 7
    jacobian = rng.normal(size=(1, 6, n))
    a = rng.normal(size=(1, n, n))
    return {
        "jacobian": jacobian,
        "q": rng.normal(size=(1, n)),
        "gravity": rng.normal(size=(1, n)),
        "mass": a @ np.swapaxes(a, -1, -2) + n * np.eye(n),
    }


def linearised_law(
    jacobian: np.ndarray,
    palm_position: np.ndarray,
    palm_quaternion: np.ndarray,
    q: np.ndarray,
    gravity: np.ndarray,
    target_position: np.ndarray,
    target_quaternion: np.ndarray,
    target_twist: np.ndarray,
    gains: GainArrays,
    rest: np.ndarray,
    mass_matrix: np.ndarray | None = None,
    dt: float = 0.0,
) -> AffineTorqueLaw:
    """The law as the controller builds it: linearised terms completed with the targets."""
    terms = impedance_terms(
        jacobian, palm_position, palm_quaternion, q, gravity, gains, rest, mass_matrix, dt
    )
    return affine_law(terms, target_position, target_quaternion, target_twist)


def test_law_at_rest_on_target_is_gravity_compensation() -> None:
    x = _random_law_inputs(0)
    quaternion = np.array([[0.0, 0.0, 0.0, 1.0]])
    position = np.array([[0.5, 0.1, 0.7]])
    gains = GainArrays.of([ImpedanceGains()])
    for mass in (None, x["mass"]):
        law = linearised_law(
            x["jacobian"],
            position,
            quaternion,
            x["q"],
            x["gravity"],
            position,
            quaternion,
            np.zeros((1, 6)),
            gains,
            x["q"],
            mass_matrix=mass,
            dt=1 / 240,
        )
        tau = law.a + (law.b @ x["q"][..., None])[..., 0]
        np.testing.assert_allclose(tau, x["gravity"], atol=1e-9)


def test_law_applies_the_task_space_spring_through_the_jacobian() -> None:
    x = _random_law_inputs(1)
    quaternion = np.array([[0.0, 0.0, 0.0, 1.0]])
    target_q = Rotation.from_rotvec([0.0, 0.0, 0.1]).as_quat()[None]
    position = np.zeros((1, 3))
    target = np.array([[0.01, -0.02, 0.005]])
    gains = ImpedanceGains(stiffness_null=0.0)
    law = linearised_law(
        x["jacobian"],
        position,
        quaternion,
        x["q"],
        np.zeros((1, 7)),
        target,
        target_q,
        np.zeros((1, 6)),
        GainArrays.of([gains]),
        x["q"],
    )
    tau = law.a + (law.b @ x["q"][..., None])[..., 0]
    wrench = np.concatenate(
        [gains.stiffness_linear * target[0], gains.stiffness_angular * np.array([0.0, 0.0, 0.1])]
    )
    np.testing.assert_allclose(tau[0], x["jacobian"][0].T @ wrench, atol=1e-9)


def test_implicit_damping_tends_to_explicit_for_small_steps() -> None:
    x = _random_law_inputs(2)
    quaternion = np.array([[0.0, 0.0, 0.0, 1.0]])
    args = (
        x["jacobian"],
        np.zeros((1, 3)),
        quaternion,
        x["q"],
        x["gravity"],
        np.zeros((1, 3)),
        quaternion,
        np.zeros((1, 6)),
        GainArrays.of([ImpedanceGains()]),
        x["q"],
    )
    explicit = linearised_law(*args)
    implicit = linearised_law(*args, mass_matrix=x["mass"], dt=1e-9)
    np.testing.assert_allclose(implicit.c, explicit.c, atol=1e-5)
    # And it damps less than the explicit law at a real step (that is what keeps it stable).
    coarse = linearised_law(*args, mass_matrix=x["mass"], dt=0.05)
    assert np.trace(-coarse.c[0]) < np.trace(-explicit.c[0])


def test_shared_joints_take_the_sum_of_both_palms_springs() -> None:
    # One body, two palms, three joints shared (a torso) and four of each arm's.
    rng = np.random.default_rng(RNG_SEED)
    shared, arm = 3, 4
    n = shared + 2 * arm
    jacobian = np.zeros((1, 12, n))
    jacobian[0, :6, :shared] = rng.normal(size=(6, shared))
    jacobian[0, :6, shared : shared + arm] = rng.normal(size=(6, arm))
    jacobian[0, 6:, :shared] = rng.normal(size=(6, shared))
    jacobian[0, 6:, shared + arm :] = rng.normal(size=(6, arm))
    identity = np.tile([0.0, 0.0, 0.0, 1.0], (1, 2, 1))
    palms = np.zeros((1, 2, 3))
    targets = np.array([[[0.01, -0.02, 0.005], [-0.01, 0.0, 0.02]]])
    gains = ImpedanceGains(stiffness_null=0.0)
    q = rng.normal(size=(1, n))
    law = linearised_law(
        jacobian,
        palms,
        identity,
        q,
        np.zeros((1, n)),
        targets,
        identity,
        np.zeros((1, 2, 6)),
        GainArrays.of_tasks([[gains, gains]]),
        q,
    )
    tau = law.a + (law.b @ q[..., None])[..., 0]
    wrench = np.concatenate(
        [1000.0 * targets[0, 0], np.zeros(3), 1000.0 * targets[0, 1], np.zeros(3)]
    )
    left = jacobian[0, :6].T @ wrench[:6]
    right = jacobian[0, 6:].T @ wrench[6:]
    np.testing.assert_allclose(tau[0], left + right, atol=1e-9)
    # The torso's columns carry both palms' torques; each arm's only its own palm's.
    np.testing.assert_allclose(tau[0, shared : shared + arm], left[shared : shared + arm])
    assert np.abs(right[:shared]).max() > 0.1 and np.abs(left[:shared]).max() > 0.1
    # Stiffness and damping couple the torso with both arms, never one arm with the other.
    assert np.abs(law.b[0, :shared, shared + arm :]).max() > 0.0
    np.testing.assert_allclose(law.b[0, shared : shared + arm, shared + arm :], 0.0, atol=1e-12)


def test_two_palms_on_one_body_without_shared_joints_is_two_bodies() -> None:
    # The coupled law over a block-diagonal body gives each block the one-palm law: the iiwa
    # pair's numbers are the general law's, not a second copy of it.
    x, y = _random_law_inputs(4), _random_law_inputs(5)
    n = 7
    quaternion = np.tile([0.0, 0.0, 0.0, 1.0], (2, 1, 1))
    target_q = Rotation.from_rotvec([[0.0, 0.1, 0.0], [0.05, 0.0, 0.0]]).as_quat()[:, None]
    palms = np.array([[[0.5, 0.2, 0.7]], [[0.5, -0.2, 0.7]]])
    targets = palms + [[[0.01, 0.0, -0.02]], [[0.0, 0.02, 0.01]]]
    twist = np.array([[[0.01, 0.0, 0.0, 0.0, 0.0, 0.1]], [[0.0, 0.0, 0.02, 0.0, 0.0, 0.0]]])
    gains = ImpedanceGains()
    two = linearised_law(
        np.concatenate([x["jacobian"], y["jacobian"]]),
        palms,
        quaternion,
        np.concatenate([x["q"], y["q"]]),
        np.concatenate([x["gravity"], y["gravity"]]),
        targets,
        target_q,
        twist,
        GainArrays.of([gains, gains]),
        np.zeros((2, n)),
        mass_matrix=np.concatenate([x["mass"], y["mass"]]),
        dt=1 / 240,
    )
    jacobian = np.zeros((1, 12, 2 * n))
    jacobian[0, :6, :n] = x["jacobian"][0]
    jacobian[0, 6:, n:] = y["jacobian"][0]
    mass = np.zeros((1, 2 * n, 2 * n))
    mass[0, :n, :n] = x["mass"][0]
    mass[0, n:, n:] = y["mass"][0]
    one = linearised_law(
        jacobian,
        palms.reshape(1, 2, 3),
        quaternion.reshape(1, 2, 4),
        np.concatenate([x["q"], y["q"]], axis=-1),
        np.concatenate([x["gravity"], y["gravity"]], axis=-1),
        targets.reshape(1, 2, 3),
        target_q.reshape(1, 2, 4),
        twist.reshape(1, 2, 6),
        GainArrays.of_tasks([[gains, gains]]),
        np.zeros((1, 2 * n)),
        mass_matrix=mass,
        dt=1 / 240,
    )
    np.testing.assert_allclose(one.a[0], two.a.reshape(-1), atol=1e-9)
    np.testing.assert_allclose(one.a_rate[0], two.a_rate.reshape(-1), atol=1e-9)
    for name in ("b", "c"):
        block = getattr(one, name)[0]
        np.testing.assert_allclose(block[:n, :n], getattr(two, name)[0], atol=1e-9)
        np.testing.assert_allclose(block[n:, n:], getattr(two, name)[1], atol=1e-9)
        np.testing.assert_allclose(block[:n, n:], 0.0, atol=1e-12)


# -- in PyBullet ----------------------------------------------------------------------------


@pytest.fixture(scope="module")
def tracking() -> dict[str, float]:
    """Step the left palm 5 cm and 10 degrees, no object; measure after 1.5 s."""
    out: dict[str, float] = {}
    with Scene(SceneSpec(objects=())) as scene:
        start = {
            Arm.LEFT: (np.array([0.6, 0.3, 0.8]), np.array(LATERAL_PALM_QUATERNIONS[Arm.LEFT])),
            Arm.RIGHT: (np.array([0.6, -0.3, 0.8]), np.array(LATERAL_PALM_QUATERNIONS[Arm.RIGHT])),
        }
        scene.place_palms(start)
        scene.step(24)
        target_p = start[Arm.LEFT][0] + [0.05, 0.0, -0.03]
        turn = Rotation.from_euler("x", 10, degrees=True)
        target_q = (turn * Rotation.from_quat(start[Arm.LEFT][1])).as_quat()
        scene.set_palm_command(Arm.LEFT, PalmCommand(target_p, target_q))
        peak = 0.0
        for _ in range(360):
            scene.step()
            torques = [scene.palm_state(arm).joint_torques for arm in (Arm.LEFT, Arm.RIGHT)]
            peak = max(peak, float(np.max(np.abs(torques))))
        state = scene.palm_state(Arm.LEFT)
        right = scene.palm_state(Arm.RIGHT)
        out["position_error"] = float(np.linalg.norm(state.position - target_p))
        out["angle_error"] = float(np.linalg.norm(quat.rotation_error(target_q, state.quaternion)))
        out["speed"] = float(np.linalg.norm(state.linear_velocity))
        out["right_drift"] = float(np.linalg.norm(right.position - start[Arm.RIGHT][0]))
        out["peak_torque"] = peak
    return out


@pytest.mark.sim
def test_palm_reaches_a_step_target(tracking: dict[str, float]) -> None:
    assert tracking["position_error"] < 0.002
    assert tracking["angle_error"] < np.radians(1.0)
    assert tracking["speed"] < 1e-3


@pytest.mark.sim
def test_other_palm_holds_still(tracking: dict[str, float]) -> None:
    assert tracking["right_drift"] < 1e-3


@pytest.mark.sim
def test_torques_stay_within_limits(tracking: dict[str, float]) -> None:
    model = build_robot_model("kuka_iiwa")
    assert tracking["peak_torque"] <= max(model.arms[Arm.LEFT].max_torque) + 1e-9


@pytest.mark.sim
def test_feed_forward_twist_tracks_a_moving_target() -> None:
    velocity = np.array([0.0, 0.0, 0.1])
    with Scene(SceneSpec(objects=())) as scene:
        quaternion = np.array(LATERAL_PALM_QUATERNIONS[Arm.LEFT])
        start = np.array([0.6, 0.3, 0.75])
        scene.place_palms({Arm.LEFT: (start, quaternion)})
        scene.step(24)
        # The command is set once; the law moves the spring anchor along the twist in between
        # re-linearisations and the target moves with the command's twist only until then.
        for k in range(120):
            t = k * 4 / 240
            scene.set_palm_command(
                Arm.LEFT, PalmCommand(start + velocity * t, quaternion, linear_velocity=velocity)
            )
            scene.step(4)
        state = scene.palm_state(Arm.LEFT)
        np.testing.assert_allclose(state.linear_velocity, velocity, atol=0.01)
        np.testing.assert_allclose(state.position, start + velocity * 2.0, atol=0.005)


@pytest.mark.sim
def test_controller_needs_enable_and_valid_arguments() -> None:
    from worlds.control import DualArmImpedanceController

    with Scene(SceneSpec(objects=())) as scene:
        with pytest.raises(ValueError, match="expected refresh_every >= 1"):
            DualArmImpedanceController(scene.robot, scene.robot_ids, 1 / 240, scene.client, None, 0)
        with pytest.raises(ValueError, match="expected 2 body ids"):
            DualArmImpedanceController(scene.robot, scene.robot_ids[:1], 1 / 240, scene.client)
        idle = DualArmImpedanceController(scene.robot, scene.robot_ids, 1 / 240, scene.client)
        with pytest.raises(RuntimeError, match="call enable"):
            idle.apply()


# -- robot model and scene ------------------------------------------------------------------


def test_kuka_model_has_two_mirrored_arms_with_palms() -> None:
    model = build_robot_model("kuka_iiwa", arm_separation=0.7, mount_height=0.6)
    left, right = model.arms[Arm.LEFT], model.arms[Arm.RIGHT]
    np.testing.assert_allclose(model.bodies[left.body].base2world_position, [0.0, 0.35, 0.6])
    np.testing.assert_allclose(model.bodies[right.body].base2world_position, [0.0, -0.35, 0.6])
    mirror = np.array([-1, 1, -1, 1, -1, 1, -1])
    np.testing.assert_allclose(np.asarray(right.rest_posture), mirror * left.rest_posture)
    text = model.bodies[0].urdf_path.read_text()
    assert '<link name="palm">' in text
    assert "<dynamics" not in text  # all damping comes from the controller
    import re
    from pathlib import Path

    meshes = re.findall(r'filename="([^"]+)"', text)
    assert meshes and all(Path(m).is_file() for m in meshes)


def test_robot_model_errors_are_explained() -> None:
    with pytest.raises(ValueError, match="expected model in"):
        build_robot_model("nao")
    with pytest.raises(ValueError, match="expected arm_separation > 0"):
        build_robot_model("kuka_iiwa", arm_separation=0.0)
    spec = build_robot_model("kuka_iiwa").arms[Arm.LEFT]
    from dataclasses import replace

    with pytest.raises(ValueError, match="expected rest_posture of length 7"):
        replace(spec, rest_posture=(0.0,))


def test_scene_spec_is_validated() -> None:
    from worlds.spec import ObstacleSpec, ShapeSpec, default_parcel

    with pytest.raises(ValueError, match="expected physics_hz a positive multiple of control_hz"):
        SceneSpec(physics_hz=240, control_hz=70)
    with pytest.raises(ValueError, match=r"expected unique names, got duplicates \['parcel'\]"):
        SceneSpec(obstacles=(ObstacleSpec("parcel", ShapeSpec.sphere(0.1), (0, 0, 1)),))
    with pytest.raises(ValueError, match="expected positive dimensions"):
        ShapeSpec.box((0.1, 0.0, 0.1))
    assert default_parcel().shape.size == (0.2, 0.3, 0.15)


@pytest.mark.sim
def test_scene_from_the_default_world_file() -> None:
    from pathlib import Path

    from worlds.world_file import load_world

    world = load_world(Path(__file__).parents[2] / "worlds" / "parcel_pick_place.yaml")
    with Scene.from_world(world) as scene:
        parcel = world.objects[0]
        position, quaternion = scene.object_pose(parcel.name)
        np.testing.assert_allclose(position, parcel.pose.position, atol=1e-9)
        np.testing.assert_allclose(quaternion, parcel.pose.quaternion_xyzw(), atol=1e-9)
        assert scene.spec.physics_hz == world.sim.physics_hz
        assert scene.active_obstacles == frozenset()
        name = world.obstacles[0].name
        body = scene.obstacle_ids[name]
        assert pb.getBasePositionAndOrientation(body, physicsClientId=scene.client)[0][2] < -50
        scene.set_active_obstacles([name])
        np.testing.assert_allclose(
            pb.getBasePositionAndOrientation(body, physicsClientId=scene.client)[0],
            world.obstacles[0].position,
        )
        assert set(scene.obstacle_overlaps()) == {name}
        with pytest.raises(ValueError, match="set_active_obstacles: expected names in"):
            scene.set_active_obstacles(["nowhere"])
        with pytest.raises(ValueError, match="expected an object name in"):
            scene.object_pose("nothing")
        # The palms start clear of the parcel: no contact force.
        scene.step(24)
        assert scene.palm_contact_force(Arm.LEFT, parcel.name) == 0.0
        with pytest.raises(RuntimeError, match="only be set before stepping"):
            scene.place_palms({})


@pytest.mark.sim
def test_obstacle_overlapping_the_parcel_is_reported() -> None:
    from worlds.spec import ObstacleSpec, ShapeSpec

    inside = ObstacleSpec("inside", ShapeSpec.sphere(0.05), (0.6, 0.0, 0.7))
    with Scene(SceneSpec(obstacles=(inside,))) as scene:
        scene.set_active_obstacles(["inside"])
        assert scene.obstacle_overlaps() == {"inside": ["parcel"]}
        scene.set_active_obstacles([])
        assert scene.obstacle_overlaps() == {}


@pytest.mark.sim
def test_turned_robot_base_still_tracks() -> None:
    """PyBullet gives Jacobians and inverse dynamics in the base frame; the law must not."""
    from worlds.spec import RobotSpec

    spec = SceneSpec(
        robot=RobotSpec(base_position=(0.1, 0.05, 0.0), base_rpy_deg=(0, 0, 20)), objects=()
    )
    with Scene(spec) as scene:
        turn = Rotation.from_euler("z", 20, degrees=True)
        target = {
            arm: (
                turn.apply([0.6, side * 0.25, 0.75]) + [0.1, 0.05, 0.0],
                (turn * Rotation.from_quat(LATERAL_PALM_QUATERNIONS[arm])).as_quat(),
            )
            for arm, side in ((Arm.LEFT, 1.0), (Arm.RIGHT, -1.0))
        }
        scene.place_palms(target)
        moved = target[Arm.LEFT][0] + [0.0, 0.0, 0.05]
        scene.set_palm_command(Arm.LEFT, PalmCommand(moved, target[Arm.LEFT][1]))
        scene.step(360)
        np.testing.assert_allclose(scene.palm_state(Arm.LEFT).position, moved, atol=0.002)
        np.testing.assert_allclose(
            scene.palm_state(Arm.RIGHT).position, target[Arm.RIGHT][0], atol=0.002
        )


@pytest.mark.sim
def test_relinearising_on_joint_motion_keeps_a_long_move_accurate() -> None:
    errors = {}
    for tolerance in (0.01, 0.0):
        with Scene(
            SceneSpec(objects=()), refresh_every=10**6, relinearise_tolerance=tolerance
        ) as s:
            quaternion = np.array(LATERAL_PALM_QUATERNIONS[Arm.LEFT])
            start = np.array([0.55, 0.3, 0.7])
            s.place_palms({Arm.LEFT: (start, quaternion)})
            target = start + [0.15, -0.05, 0.15]
            s.set_palm_command(Arm.LEFT, PalmCommand(target, quaternion))
            s.step(480)
            errors[tolerance] = float(np.linalg.norm(s.palm_state(Arm.LEFT).position - target))
    assert errors[0.01] < 0.002
    # Never re-linearised, the 20 cm move ends off target: the tolerance is what fixes it.
    assert errors[0.0] > 5 * errors[0.01]


@pytest.mark.sim
@pytest.mark.parametrize("degrees_from_limit", [5.0, 8.0])
def test_a_wrist_near_its_limit_does_not_turn_the_palm(degrees_from_limit: float) -> None:
    # A turned grip holds the left wrist (joint 6) a few degrees from its limit. The joint-limit
    # repulsion acts on the joint, so within its band it turns the palm off its command: with a
    # 0.15 rad band, 2.9 degrees at 5 degrees from the limit, unloaded (and 6-8 under a squeeze,
    # enough to roll a held box out of the palms).
    with Scene(SceneSpec(objects=())) as scene:
        spec = scene.robot.arms[Arm.LEFT]
        body, client = scene.robot_ids[spec.body], scene.client
        q = np.radians([-12.0, 89.0, -1.0, -18.0, 106.0, 0.0, -62.0])
        q[5] = spec.lower[5] + np.radians(degrees_from_limit)
        for joint, value in zip(spec.joint_indices, q, strict=True):
            pb.resetJointState(body, joint, float(value), 0.0, physicsClientId=client)
        link = pb.getLinkState(
            body, spec.palm_link, computeForwardKinematics=1, physicsClientId=client
        )
        position, quaternion = np.array(link[4]), np.array(link[5])
        scene.controller.set_rest_posture(Arm.LEFT, q)
        scene.controller.set_command(Arm.LEFT, PalmCommand(position, quaternion))
        scene.controller.refresh()
        scene.step(240)
        state = scene.palm_state(Arm.LEFT)
        turned = np.linalg.norm(quat.rotation_error(quaternion, state.quaternion))
        assert np.degrees(turned) < 0.2
        assert np.linalg.norm(state.position - position) < 5e-4


@pytest.mark.sim
def test_a_palm_held_still_by_a_load_meets_the_static_stiffness_the_law_reports() -> None:
    """Pushed up by 5 N (PyBullet's external force on the palm link, every physics step), a
    palm holding its pose settles where ``static_palm_stiffness`` says: the stated 1000 N/m
    scaled by the implicit damping, which assumes the joints free to accelerate."""
    spec = SceneSpec(objects=())
    with Scene(spec) as scene:
        target = {
            arm: (np.array([0.6, side * 0.2, 0.8]), np.array(LATERAL_PALM_QUATERNIONS[arm]))
            for arm, side in ((Arm.LEFT, 1.0), (Arm.RIGHT, -1.0))
        }
        scene.place_palms(target)
        scene.step(240)
        controller = scene.controller
        before = scene.palm_state(Arm.LEFT).position
        stiffness = controller.static_palm_stiffness()[Arm.LEFT]
        # The stated spring in the task space, less what the implicit damping takes from it.
        assert stiffness.shape == (3, 3)
        assert 500.0 < stiffness[2, 2] < 980.0
        push = np.array([0.0, 0.0, 5.0])
        spec_left = scene.robot.arms[Arm.LEFT]
        body = scene.robot_ids[spec_left.body]
        for _ in range(720):
            at = pb.getLinkState(body, spec_left.palm_link, physicsClientId=scene.client)[0]
            pb.applyExternalForce(
                body, spec_left.palm_link, push, at, pb.WORLD_FRAME, physicsClientId=scene.client
            )
            scene.step(1)
        moved = scene.palm_state(Arm.LEFT).position - before
        expected = np.linalg.solve(controller.static_palm_stiffness()[Arm.LEFT], push)
        np.testing.assert_allclose(moved, expected, atol=0.02 * np.linalg.norm(expected))
        assert moved[2] > 1.05 * push[2] / 1000.0  # softer than the stated gain
