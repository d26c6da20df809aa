"""The iCub model: loads, tracks palm poses, and lifts a parcel by contact alone.

The parcel, table and squeeze come from ``worlds/icub_parcel_pick_place.yaml``; the palms
follow scripted minimum-jerk targets as in :mod:`tests.worlds.test_grasp` (no constraints, no
teleporting).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import pybullet as pb
import pytest
from numpy.typing import NDArray

from skills import quaternion as quat
from skills.vocabulary import ARMS, Arm
from tests.worlds.test_grasp import Log, minimum_jerk, tilt_deg
from worlds.collision import CollisionWorld, welded_links
from worlds.control import PalmCommand
from worlds.palm_poses import lateral_grasp_palm_poses
from worlds.robots.icub import ARM_JOINTS, TORSO_JOINTS
from worlds.scene import Scene
from worlds.sim_world import SimWorld
from worlds.world_file import World, as_world_spec, load_world, world_from_data

pytestmark = pytest.mark.sim

WORLD = Path(__file__).resolve().parents[2] / "worlds" / "icub_parcel_pick_place.yaml"
PARCEL = "parcel"
SQUEEZE = 0.015  # target this far inside the face, m


@pytest.fixture(scope="module")
def world() -> World:
    return load_world(WORLD)


def icub_scene(world: World) -> Scene:
    return Scene.from_world(world)  # the model's own gains (RobotModel.gain_overrides)


def start(world: World) -> tuple[NDArray[np.float64], float, float]:
    """Parcel centre (3,), half its extent along y and the palm thickness, m."""
    parcel = world.objects[0]
    half_span = float(parcel.shape.size[1]) / 2.0  # type: ignore[union-attr]
    return np.asarray(parcel.pose.position, float), half_span, float(world.robot.palm_size[2])


def test_icub_loads_as_one_body_with_torso_and_two_arms(world: World) -> None:
    with icub_scene(world) as scene:
        assert scene.robot.name == "icub"
        assert len(scene.robot_ids) == 1  # torso and both arms under one controller
        body = scene.robot_ids[0]
        c = scene.client
        infos = [
            pb.getJointInfo(body, j, physicsClientId=c)
            for j in range(pb.getNumJoints(body, physicsClientId=c))
        ]
        movable = [i[1].decode() for i in infos if i[2] != pb.JOINT_FIXED]
        arms = [f"{side}_{name}" for side in "lr" for name in ARM_JOINTS]
        assert movable == [*TORSO_JOINTS, *arms]
        for arm, side in ((Arm.LEFT, "l"), (Arm.RIGHT, "r")):
            spec = scene.robot.arms[arm]
            names = [infos[j][1].decode() for j in spec.joint_indices]
            assert names == [f"{side}_{name}" for name in ARM_JOINTS]
            assert infos[spec.palm_link][12] == f"{side}_palm".encode()
        assert scene.controller.driven_joint_count == 17
        # The legs do not move: fixed joints on the fixed waist (the head rides on the torso).
        legs = [j for j, i in enumerate(infos) if i[1].decode().startswith(("l_", "r_"))][:16]
        assert all(infos[j][2] == pb.JOINT_FIXED for j in legs)
        before = [pb.getLinkState(body, j, physicsClientId=c)[4] for j in legs]
        scene.step(240)
        after = [pb.getLinkState(body, j, physicsClientId=c)[4] for j in legs]
        np.testing.assert_allclose(after, before, atol=1e-12)
        # No link of the robot touches the table, and the arms do not touch each other.
        assert not pb.getContactPoints(bodyA=body, bodyB=scene.table_id, physicsClientId=c)
        assert not pb.getContactPoints(bodyA=body, bodyB=body, physicsClientId=c)


def test_forearm_collision_shapes_reach_fcl(world: World) -> None:
    with icub_scene(world) as scene:
        names = CollisionWorld(scene).element_names
    for link in ("l_forearm", "l_hand", "palm"):
        assert f"left_arm/{link}" in names
    for link in ("r_forearm", "r_hand", "palm"):
        assert f"right_arm/{link}" in names


def test_palms_hold_commanded_poses_within_5_mm(world: World) -> None:
    centre, half_span, thickness = start(world)
    with icub_scene(world) as scene:
        scene.place_palms(lateral_grasp_palm_poses(centre, half_span, thickness, gap=0.04))
        # A new target 3 cm up and 2 cm forward, reached and held under impedance control.
        target = lateral_grasp_palm_poses(
            centre + np.array([0.02, 0.0, 0.03]), half_span, thickness, gap=0.04
        )
        for arm, (position, quaternion) in target.items():
            scene.set_palm_command(arm, PalmCommand(position, quaternion))
        scene.step(240)
        errors = []
        for _ in range(4):
            scene.step(120)
            for arm in ARMS:
                errors.append(np.linalg.norm(scene.palm_state(arm).position - target[arm][0]))
        assert max(errors) < 0.005, f"palm error {max(errors) * 1000:.2f} mm"


@dataclass(frozen=True)
class Lift:
    before_lift: NDArray[np.float64]
    height_after_lift: float
    logs: tuple[Log, ...]
    hold: Log


def parcel_in_palms(scene: Scene) -> NDArray[np.float64]:
    position, _ = scene.object_pose(PARCEL)
    palms = [scene.palm_state(arm).position for arm in ARMS]
    return position - 0.5 * (palms[0] + palms[1])


def segment(
    scene: Scene,
    grasp: tuple[float, float],
    c0: NDArray[np.float64],
    c1: NDArray[np.float64],
    g0: float,
    g1: float,
    squeeze: float,
    duration: float,
    log: Log | None = None,
) -> None:
    """Palms along a minimum-jerk path of the grasp centre from ``c0`` to ``c1`` (3,), their
    gap from ``g0`` to ``g1``, m, ``grasp`` the parcel's half span and the palm thickness, m;
    logged every 24 steps into ``log``."""
    half_span, thickness = grasp
    per_command = scene.spec.physics_hz // scene.spec.control_hz
    steps = round(duration * scene.spec.physics_hz)
    for k in range(0, steps, per_command):
        s = float(minimum_jerk((k + per_command) / steps))
        poses = lateral_grasp_palm_poses(
            c0 + (c1 - c0) * s, half_span, thickness, g0 + (g1 - g0) * s
        )
        for arm, (p, q) in poses.items():
            scene.set_palm_command(arm, PalmCommand(p, q, squeeze_offset=squeeze))
        for _ in range(per_command):
            scene.step()
            if log is not None and scene.step_count % 24 == 0:
                log.time.append(scene.time)
                log.parcel_in_palms.append(parcel_in_palms(scene))
                log.tilt_deg.append(tilt_deg(scene))
                for arm in ARMS:
                    log.force[arm].append(scene.palm_contact_force(arm, PARCEL))


def run_lift(world: World, carry: NDArray[np.float64]) -> Lift:
    """Approach, squeeze, lift 6 cm, hold 3 s, carry along ``carry`` (3,), m, in 1.5 s."""
    centre, half_span, thickness = start(world)
    with icub_scene(world) as scene:
        scene.place_palms(lateral_grasp_palm_poses(centre, half_span, thickness, gap=0.05))
        scene.step(48)
        segment(scene, (half_span, thickness), centre, centre, 0.05, 0.0, 0.0, 1.0)
        segment(scene, (half_span, thickness), centre, centre, 0.0, 0.0, SQUEEZE, 0.5)
        before = parcel_in_palms(scene)
        up = centre + np.array([0.0, 0.0, 0.06])
        side = up + carry
        lifting, hold, moving = Log(), Log(), Log()
        segment(scene, (half_span, thickness), centre, up, 0.0, 0.0, SQUEEZE, 1.5, lifting)
        height = float(scene.object_pose(PARCEL)[0][2])
        segment(scene, (half_span, thickness), up, up, 0.0, 0.0, SQUEEZE, 3.0, hold)
        segment(scene, (half_span, thickness), up, side, 0.0, 0.0, SQUEEZE, 1.5, moving)
        return Lift(before, height, (lifting, hold, moving), hold)


def parcel_moved(world: World, offset: tuple[float, float, float]) -> World:
    """``world`` with its parcel starting ``offset`` (3,) m from where the file puts it."""
    data = world.model_dump(mode="json")
    pose = data["objects"][0]["pose"]
    pose["position"] = [v + d for v, d in zip(pose["position"], offset, strict=True)]
    return world_from_data(data, world.source)


@pytest.fixture(scope="module")
def lift(world: World) -> Lift:
    """At the centre: approach, squeeze, lift 6 cm, hold 3 s, carry 5 cm along +y."""
    return run_lift(world, np.array([0.0, 0.05, 0.0]))


@pytest.fixture(scope="module")
def side_lift(world: World) -> tuple[World, Lift]:
    """The same 10 cm to the robot's left (+y), carried 5 cm further out: the palms there
    need the torso (the trial goals lie this far to either side)."""
    moved = parcel_moved(world, (0.0, 0.10, 0.0))
    return moved, run_lift(moved, np.array([0.0, 0.05, 0.0]))


@pytest.fixture(params=["centre", "side"])
def lifted(request: pytest.FixtureRequest, world: World) -> tuple[World, Lift]:
    """The lift at the centre, and 10 cm to the side."""
    if request.param == "centre":
        return world, request.getfixturevalue("lift")
    side: tuple[World, Lift] = request.getfixturevalue("side_lift")
    return side


def test_icub_lifts_the_parcel(lifted: tuple[World, Lift]) -> None:
    world, lift = lifted
    centre, _, _ = start(world)
    # 6 cm less the palms' sag under the parcel's weight.
    np.testing.assert_allclose(lift.height_after_lift, centre[2] + 0.06, atol=0.01)


def test_parcel_does_not_slip_or_tilt_in_icub_palms(lifted: tuple[World, Lift]) -> None:
    _, lift = lifted
    offsets = np.concatenate([np.asarray(log.parcel_in_palms) for log in lift.logs])
    slip = np.linalg.norm(offsets - lift.before_lift, axis=1)
    assert slip.max() < 0.01, f"slip {slip.max() * 1000:.2f} mm"
    tilts = [t for log in lift.logs for t in log.tilt_deg]
    assert max(tilts) < 5.0, f"tilt {max(tilts):.2f} deg"


def test_icub_squeeze_is_steady_during_hold(lifted: tuple[World, Lift]) -> None:
    _, lift = lifted
    for arm in ARMS:
        force = np.asarray(lift.hold.force[arm])
        assert np.all((force > 5.0) & (force < 60.0)), (
            f"{arm}: {force.min():.1f}..{force.max():.1f} N"
        )


# -- the torso in the loop --------------------------------------------------------------------


def empty_scene(world: World) -> Scene:
    """The iCub world's scene without its parcel (the palms move through where it was)."""
    spec = as_world_spec(world).scene
    return Scene(replace(spec, objects=()))


def arm_chain(scene: Scene, arm: Arm) -> tuple[NDArray[np.float64], float]:
    """An arm's shoulder (its first joint's frame, (3,) m) and the summed lengths of its links
    to the palm, m: no posture of the arm alone puts the palm farther from that shoulder."""
    body, c = scene.robot_ids[0], scene.client
    spec = scene.robot.arms[arm]
    links = [*range(spec.joint_indices[0], spec.palm_link + 1)]
    frames = np.array([pb.getLinkState(body, j, physicsClientId=c)[4] for j in links])
    return frames[0], float(np.linalg.norm(np.diff(frames, axis=0), axis=1).sum())


def torso(scene: Scene) -> NDArray[np.float64]:
    """The torso joints' positions (pitch, roll, yaw), rad."""
    return scene.controller.joint_positions()[: len(TORSO_JOINTS)]


def test_the_torso_takes_the_palms_beyond_the_arms_reach(world: World) -> None:
    centre, half_span, thickness = start(world)
    far = np.array([0.45, 0.0, 0.70])  # ahead of the table's middle, low
    with empty_scene(world) as scene:
        scene.place_palms(lateral_grasp_palm_poses(centre, half_span, thickness, gap=0.02))
        target = lateral_grasp_palm_poses(far, half_span, thickness, gap=0.02)
        for arm in ARMS:
            shoulder, length = arm_chain(scene, arm)
            # Out of the arm's reach from its shoulder with the torso upright, by over 2 cm.
            assert np.linalg.norm(target[arm][0] - shoulder) > length + 0.02
        segment(scene, (half_span, thickness), centre, far, 0.02, 0.02, 0.0, 2.0)
        scene.step(240)
        errors = [np.linalg.norm(scene.palm_state(a).position - target[a][0]) for a in ARMS]
        assert max(errors) < 0.003, f"palm error {max(errors) * 1000:.2f} mm"
        assert torso(scene)[0] > 0.3  # it leans forward to get there
        ctl = scene.controller
        q = ctl.joint_positions()
        assert np.all((q >= ctl._lower - 1e-3) & (q <= ctl._upper + 1e-3))


def test_the_torso_stays_upright_while_the_palms_hold_still(world: World) -> None:
    centre, half_span, thickness = start(world)
    with empty_scene(world) as scene:
        scene.place_palms(lateral_grasp_palm_poses(centre, half_span, thickness, gap=0.02))
        scene.step(24)
        start_torso = torso(scene)
        worst = 0.0
        for _ in range(20):
            scene.step(24)
            worst = max(worst, float(np.abs(torso(scene) - start_torso).max()))
        # Within 0.5 degrees of where it started, and 3 degrees of upright.
        assert worst < np.radians(0.5), f"torso moved {np.degrees(worst):.3f} deg"
        assert np.abs(torso(scene)).max() < np.radians(3.0), np.degrees(torso(scene))


def test_the_hand_welded_to_each_palm_is_a_sphere_above_and_behind_it(world: World) -> None:
    with icub_scene(world) as scene:
        collision = CollisionWorld(scene)
        for arm, side in ((Arm.LEFT, "l"), (Arm.RIGHT, "r")):
            spec = scene.robot.arms[arm]
            body = scene.robot_ids[spec.body]
            welded = welded_links(body, spec.palm_link, scene.client)
            names = {
                pb.getJointInfo(body, k, physicsClientId=scene.client)[12].decode() for k in welded
            }
            assert f"{side}_hand" in names  # the palm's own link and the hand, nothing movable
            assert f"{side}_wrist_1" not in names
            palm = scene.palm_state(arm)
            centres, radii = collision.welded_spheres(arm, palm.position, palm.quaternion)
            assert centres.shape == (1, 3) and radii.shape == (1,)
            # The palm frame's x points down in the grasp and z into the object: the hand
            # stands above the palm (-x) and behind its face (-z), larger than the palm box.
            assert centres[0, 0] < -0.02 and centres[0, 2] < 0.0
            assert radii[0] > float(np.max(world.robot.palm_size))
            # Put back in the world, the sphere is centred on the hand's collision geometry.
            hand = next(k for k in welded if k != spec.palm_link)
            low, high = (np.asarray(v) for v in pb.getAABB(body, hand, scene.client))
            centre = palm.position + quat.to_matrix(palm.quaternion) @ centres[0]
            assert np.linalg.norm((low + high) / 2.0 - centre) < 0.03


def test_the_reasoner_sees_the_hands_ride_along_the_palms(world: World) -> None:
    with SimWorld(world) as sim:
        query = sim.scene_query()
        for arm in ARMS:
            centres, radii = sim.welded_spheres(arm)
            hand_centres, hand_radii = query.hands[arm]
            np.testing.assert_array_equal(hand_centres, centres)
            np.testing.assert_array_equal(hand_radii, radii)
