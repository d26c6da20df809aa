"""FCL collision world: agreement with PyBullet, group distances, trajectory and point queries."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np
import pybullet as pb
import pytest

from skills import quaternion as quat
from skills.vocabulary import Arm
from worlds.collision import OBSTACLES, TABLE, CollisionWorld, arm_group
from worlds.palm_poses import LATERAL_PALM_QUATERNIONS, lateral_grasp_palm_poses
from worlds.scene import Scene
from worlds.spec import ObstacleSpec, SceneSpec, ShapeSpec

pytestmark = pytest.mark.sim

OBSTACLE_SPECS = (
    ObstacleSpec("ball", ShapeSpec.sphere(0.05), (0.6, 0.0, 0.9)),
    ObstacleSpec("block", ShapeSpec.box((0.1, 0.2, 0.1)), (0.45, -0.3, 1.0)),
    ObstacleSpec("post", ShapeSpec.cylinder(0.04, 0.3), (0.5, 0.35, 0.85)),
)


@pytest.fixture(scope="module")
def world() -> Iterator[CollisionWorld]:
    with Scene(SceneSpec(obstacles=OBSTACLE_SPECS)) as scene:
        scene.set_active_obstacles(["ball", "block", "post"])
        yield CollisionWorld(scene)


def _set_random_configuration(scene: Scene, rng: np.random.Generator) -> None:
    # Test setup only: the run itself never resets joints.
    for arm in (Arm.LEFT, Arm.RIGHT):
        spec = scene.robot.arms[arm]
        body = scene.robot_ids[spec.body]
        q = rng.uniform(0.8 * np.asarray(spec.lower), 0.8 * np.asarray(spec.upper))
        for joint, value in zip(spec.joint_indices, q, strict=True):
            pb.resetJointState(body, joint, float(value), 0.0, physicsClientId=scene.client)


def _pybullet_distance(scene: Scene, body_a: int, body_b: int) -> float:
    points = pb.getClosestPoints(body_a, body_b, 10.0, physicsClientId=scene.client)
    return min(p[8] for p in points)


def test_distances_agree_with_pybullet_on_random_configurations(world: CollisionWorld) -> None:
    scene = world.scene
    rng = np.random.default_rng(7)
    checked = 0
    worst = 0.0
    for _ in range(20):
        _set_random_configuration(scene, rng)
        world.sync()
        for arm in (Arm.LEFT, Arm.RIGHT):
            body = scene.robot_ids[scene.robot.arms[arm].body]
            for group, others in (
                (OBSTACLES, scene.obstacle_ids.values()),
                (TABLE, [scene.table_id]),
            ):
                expected = min(_pybullet_distance(scene, body, other) for other in others)
                got = world.distance(arm_group(arm), group).distance
                if expected < 0.0:
                    # Penetration depths come from different algorithms; agree on the sign.
                    assert got <= 1e-6
                    continue
                worst = max(worst, abs(got - expected))
                assert got == pytest.approx(expected, abs=0.002), (arm, group)
                checked += 1
    assert checked >= 60
    assert worst < 0.002


def test_link_distances_match_the_group_distance(world: CollisionWorld) -> None:
    scene = world.scene
    _set_random_configuration(scene, np.random.default_rng(11))
    world.sync()
    for arm in (Arm.LEFT, Arm.RIGHT):
        links = world.link_distances(arm)
        assert links.links == world.arm_links(arm)
        assert links.links[-1] == f"{arm_group(arm)}/palm"
        assert links.distances.shape == (len(links.links),)
        closest = world.distance(arm_group(arm), OBSTACLES)
        assert links.distances.min() == pytest.approx(closest.distance, abs=1e-9)
        k = int(np.argmin(links.distances))
        np.testing.assert_allclose(
            np.linalg.norm(links.link_points[k] - links.obstacle_points[k]),
            max(links.distances[k], 0.0),
            atol=1e-6,
        )


def test_closest_points_lie_at_the_reported_distance(world: CollisionWorld) -> None:
    scene = world.scene
    _set_random_configuration(scene, np.random.default_rng(5))
    world.sync()
    found = world.distance("left_arm", TABLE)
    if found.distance > 0:
        np.testing.assert_allclose(
            np.linalg.norm(found.point_a - found.point_b), found.distance, atol=1e-6
        )
    # The table's closest point is on (or in) the table box.
    table = scene.spec.table
    assert found.point_b[2] <= table.position[2] + 1e-6


def test_palms_squeezing_the_parcel_are_reported_in_contact() -> None:
    with Scene(SceneSpec()) as scene:
        scene.place_palms(lateral_grasp_palm_poses((0.6, 0.0, 0.675), 0.15, 0.02, gap=-0.005))
        world = CollisionWorld(scene)
        pairs = world.colliding_pairs()
        assert ("left_arm/palm", "parcel") in pairs
        assert ("right_arm/palm", "parcel") in pairs
        assert world.distance("left_arm", "parcel").distance < 0.0
    with Scene(SceneSpec()) as scene:
        scene.place_palms(lateral_grasp_palm_poses((0.6, 0.0, 0.675), 0.15, 0.02, gap=0.03))
        world = CollisionWorld(scene)
        assert world.colliding_pairs(["left_arm", "right_arm", "parcel"]) == []
        assert world.distance("left_arm", "parcel").distance == pytest.approx(0.03, abs=1e-3)


def _lift_trajectory(n: int, rise: float) -> tuple[np.ndarray, ...]:
    s = np.linspace(0.0, 1.0, n)
    centre = np.stack([np.full(n, 0.6), np.zeros(n), 0.675 + rise * s], axis=1)
    offset = np.array([0.0, 0.16, 0.0])
    palms = np.stack([centre + offset, centre - offset], axis=1)
    quaternions = np.broadcast_to(
        np.array([LATERAL_PALM_QUATERNIONS[Arm.LEFT], LATERAL_PALM_QUATERNIONS[Arm.RIGHT]]),
        (n, 2, 4),
    )
    parcel_q = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
    return palms, quaternions, centre, parcel_q


def test_trajectory_check_finds_the_first_collision(world: CollisionWorld) -> None:
    palms, quaternions, centre, parcel_q = _lift_trajectory(1000, 0.4)
    result = world.check_trajectory(palms, quaternions, "parcel", centre, parcel_q)
    # The parcel's top (0.75 + 0.4 s) meets the ball's bottom (0.85) at s = 0.25.
    assert abs(result.first_collision - 250) <= 1
    assert not result.collision_free
    assert result.collides[: result.first_collision].sum() == 0
    assert result.first_pair == ("parcel", "ball")  # what met what, for a refusal to name
    with_margin = world.check_trajectory(palms, quaternions, "parcel", centre, parcel_q, 0.02)
    # 2 cm earlier: s = 0.2.
    assert abs(with_margin.first_collision - 200) <= 1
    # Without the parcel, the palms alone pass beside the ball.
    beside = world.check_trajectory(palms, quaternions)
    assert beside.collision_free and beside.first_pair is None


def test_trajectory_check_ignores_inactive_obstacles(world: CollisionWorld) -> None:
    scene = world.scene
    palms, quaternions, centre, parcel_q = _lift_trajectory(200, 0.4)
    scene.set_active_obstacles(["block"])
    world.sync()
    try:
        assert world.check_trajectory(palms, quaternions, "parcel", centre, parcel_q).collision_free
    finally:
        scene.set_active_obstacles(["ball", "block", "post"])
        world.sync()


@contextmanager
def _no_obstacles(world: CollisionWorld) -> Iterator[None]:
    """The parcel alone on the table: what a path check sees is the parcel where it rests."""
    world.scene.set_active_obstacles([])
    world.sync()
    try:
        yield
    finally:
        world.scene.set_active_obstacles(["ball", "block", "post"])
        world.sync()


def _left_palm_along_y(n: int, y0: float, y1: float) -> tuple[np.ndarray, np.ndarray]:
    """The left palm carried from y0 to y1 at the parcel's centre height, in front of its
    x = 0.6 centre line; the right palm stands far off (y = -0.6)."""
    y = np.linspace(y0, y1, n)
    palms = np.stack(
        [np.stack([np.full(n, 0.6), y, np.full(n, 0.675)], 1), np.tile([0.6, -0.6, 0.675], (n, 1))],
        axis=1,
    )
    quaternions = np.broadcast_to(
        np.array([LATERAL_PALM_QUATERNIONS[Arm.LEFT], LATERAL_PALM_QUATERNIONS[Arm.RIGHT]]),
        (n, 2, 4),
    )
    return palms, quaternions


def test_a_path_keeps_clear_of_a_resting_object_it_is_asked_to_avoid(
    world: CollisionWorld,
) -> None:
    # The parcel's +y face is at y = 0.15: a palm swept from y = 0.45 to 0 goes through it.
    palms, quaternions = _left_palm_along_y(301, 0.45, 0.0)
    with _no_obstacles(world):
        assert world.check_trajectory(palms, quaternions).collision_free
        through = world.check_trajectory(palms, quaternions, avoid=["parcel"], avoid_margin=0.01)
        assert not through.collision_free
        # The palm's face (half its 2 cm thickness from its centre) comes within 1 cm of the
        # face at y = 0.15 + 0.01 + 0.01: step (0.45 - 0.17) / 0.0015, give or take its corners.
        first = through.first_collision
        assert 170 <= first <= 190, first
        assert not through.collides[:first].any()
        assert through.first_pair == ("the left palm", "parcel")
        # Asked only not to touch it: 1 cm later, 6 or 7 steps on.
        touching = world.check_trajectory(palms, quaternions, avoid=["parcel"])
        assert 5 <= touching.first_collision - first <= 8, (touching.first_collision, first)
        # The obstacles' margin is not the objects'.
        assert (
            world.check_trajectory(
                palms, quaternions, margin=0.05, avoid=["parcel"]
            ).first_collision
            == touching.first_collision
        )
        # The held object is never its own obstacle.
        centre = np.tile([0.6, 0.0, 0.675], (len(palms), 1))
        upright = np.tile([0.0, 0.0, 0.0, 1.0], (len(palms), 1))
        held = world.check_trajectory(
            palms, quaternions, "parcel", centre, upright, 0.01, ["parcel"], 0.01
        )
        assert held.collides.sum() < through.collides.sum()


def test_a_palm_that_starts_on_the_resting_object_is_free_of_it(world: CollisionWorld) -> None:
    with _no_obstacles(world):
        # Just let go, against the +y face: backing away is clear, as is staying.
        leaving, q = _left_palm_along_y(50, 0.16, 0.30)
        avoid = {"avoid": ["parcel"], "avoid_margin": 0.01}
        assert world.check_trajectory(leaving, q, **avoid).collision_free
        # Starting 5 mm off the face, it may keep or widen the gap, never narrow it.
        near, q = _left_palm_along_y(50, 0.175, 0.30)
        assert world.check_trajectory(near, q, **avoid).collision_free
        closing, q = _left_palm_along_y(50, 0.175, 0.168)
        assert not world.check_trajectory(closing, q, **avoid).collision_free


def test_only_objects_can_be_avoided(world: CollisionWorld) -> None:
    palms, quaternions = _left_palm_along_y(5, 0.45, 0.4)
    with pytest.raises(ValueError, match=r"expected objects in \['parcel'\], got \['ball'\]"):
        world.check_trajectory(palms, quaternions, avoid=["ball"])


def test_trajectory_check_validates_shapes(world: CollisionWorld) -> None:
    with pytest.raises(ValueError, match=r"expected palm_positions of shape \(N, 2, 3\)"):
        world.check_trajectory(np.zeros((5, 3)), np.zeros((5, 2, 4)))
    with pytest.raises(ValueError, match="expected object poses with object_name"):
        world.check_trajectory(np.zeros((5, 2, 3)), np.zeros((5, 2, 4)), "parcel")


def test_point_query_gives_distance_and_closest_point(world: CollisionWorld) -> None:
    points = np.array(
        [
            [0.6, 0.0, 1.0],  # 5 cm above the ball's top
            [0.45, -0.3, 1.1],  # 5 cm above the block's top
            [0.6, 0.35, 0.85],  # 10 cm from the post's axis, 6 cm from its side
            [0.6, 0.0, 0.9],  # the ball's centre: inside
        ]
    )
    distances, closest = world.query(points)
    np.testing.assert_allclose(distances, [0.05, 0.05, 0.06, -0.05], atol=1e-4)
    np.testing.assert_allclose(closest[0], [0.6, 0.0, 0.95], atol=1e-6)
    np.testing.assert_allclose(closest[1], [0.45, -0.3, 1.05], atol=1e-6)
    np.testing.assert_allclose(closest[2], [0.54, 0.35, 0.85], atol=1e-4)
    with pytest.raises(ValueError, match=r"expected points of shape \(N, 3\)"):
        world.query(np.zeros(3))


def test_unknown_group_is_explained(world: CollisionWorld) -> None:
    with pytest.raises(ValueError, match="expected a group in"):
        world.distance("left_arm", "nonsense")


def _solve_palm(scene: Scene, arm: Arm, position: np.ndarray, quaternion: np.ndarray) -> float:
    """Best palm position error over a few IK starts, m (test setup resets the joints)."""
    spec = scene.robot.arms[arm]
    body = scene.robot_ids[spec.body]
    rng = np.random.default_rng(0)
    lower, upper = np.asarray(spec.lower), np.asarray(spec.upper)
    best = np.inf
    for start in range(4):
        seed = (
            np.asarray(spec.rest_posture) if start == 0 else rng.uniform(0.7 * lower, 0.7 * upper)
        )
        for joint, value in zip(spec.joint_indices, seed, strict=True):
            pb.resetJointState(body, joint, float(value), physicsClientId=scene.client)
        for _ in range(3):
            q = pb.calculateInverseKinematics(
                body, spec.palm_link, position.tolist(), quaternion.tolist(),
                lowerLimits=list(lower), upperLimits=list(upper), jointRanges=list(upper - lower),
                restPoses=seed.tolist(), maxNumIterations=300, residualThreshold=1e-7,
                physicsClientId=scene.client,
            )  # fmt: skip
            for joint, value in zip(spec.joint_indices, q, strict=True):
                pb.resetJointState(body, joint, float(value), physicsClientId=scene.client)
        link = pb.getLinkState(
            body, spec.palm_link, computeForwardKinematics=1, physicsClientId=scene.client
        )
        best = min(best, float(np.linalg.norm(np.asarray(link[4]) - position)))
        if best < 1e-3:
            break
    return best


def test_palms_reach_the_parcel_sides_over_the_table_workspace() -> None:
    """Parcel centres at the corners of x 0.45..0.8, y -0.2..0.2, z 0.675..0.95; table clear."""
    with Scene(SceneSpec(objects=())) as scene:
        world = CollisionWorld(scene)
        worst = 0.0
        for x in (0.45, 0.8):
            for y in (-0.2, 0.2):
                for z in (0.675, 0.95):
                    poses = lateral_grasp_palm_poses((x, y, z), 0.15, 0.02)
                    for arm, (position, quaternion) in poses.items():
                        worst = max(worst, _solve_palm(scene, arm, position, quaternion))
                    world.sync()
                    for arm in (Arm.LEFT, Arm.RIGHT):
                        assert world.distance(arm_group(arm), TABLE).distance > 0.0, (x, y, z)
        # Upright bases missed the far low corner by 5 cm; the 9 degree lean brings it in.
        assert worst < 0.012


def _left_palm_path(scene: Scene, shift: np.ndarray, n: int = 40) -> tuple[np.ndarray, np.ndarray]:
    """Both palms held where they are, the left one moved linearly by ``shift`` (3,), m."""
    states = [scene.palm_state(arm) for arm in (Arm.LEFT, Arm.RIGHT)]
    positions = np.repeat(np.array([[s.position for s in states]]), n, axis=0)
    positions[:, 0] += np.linspace(0.0, 1.0, n)[:, None] * shift
    quaternions = np.repeat(np.array([[s.quaternion for s in states]]), n, axis=0)
    return positions, quaternions


@contextmanager
def _ball_above_left_wrist() -> Iterator[tuple[Scene, CollisionWorld]]:
    """A ball 16 cm above the left palm at rest (6 cm above its wrist), present and synced."""
    with Scene(SceneSpec()) as bare:
        palm = np.asarray(bare.palm_state(Arm.LEFT).position, dtype=float)
    ball = ObstacleSpec("ball", ShapeSpec.sphere(0.03), tuple(palm + [0.0, 0.0, 0.16]))
    with Scene(SceneSpec(obstacles=(ball,))) as scene:
        scene.set_active_obstacles(["ball"])
        world = CollisionWorld(scene)
        world.sync()
        yield scene, world


def test_carried_forearms_start_where_they_are_and_may_not_narrow_their_gap() -> None:
    # A ball 6 cm above the left wrist: a forearm margin wider than the gap it starts with.
    with _ball_above_left_wrist() as (scene, world):
        wrist = world.link_distances(Arm.LEFT).distances[-5:-1]  # the carried links
        start_gap = float(wrist.min())
        assert 0.01 < start_gap < 0.2
        margin = start_gap + 0.03
        down, q = _left_palm_path(scene, np.array([0.0, 0.0, -0.05]))
        up, _ = _left_palm_path(scene, np.array([0.0, 0.0, 0.05]))
        # Moving away keeps the gap it starts with: clear, though inside the margin.
        assert not world.check_attached_links(down, q, 4, margin).any()
        # Moving towards narrows it: refused, at the step where it is 2 mm nearer than at first.
        toward = world.check_attached_links(up, q, 4, margin)
        assert not toward[0] and toward[-1]
        # Far from the ball a margin below the gap asks nothing of the start.
        assert not world.check_attached_links(down, q, 4, start_gap - 0.01).any()
        # The first command 3 cm ahead of the palm (a squeezing grip) does not move the
        # links: they start where they are, so a path that stands still is clear.
        ahead = up.copy()
        ahead[:] = up[-1] - [0.0, 0.0, 0.02]
        assert not world.check_attached_links(ahead, q, 4, margin).any()


def test_link_frames_posed_as_the_rigid_carry_give_its_answer() -> None:
    """check_link_frames (links posed by predicted frames, as the iCub's IK prediction poses
    them) and check_attached_links (the rigid carry) share one check: link frames carried
    rigidly with the palm give the same verdict at every waypoint, towards and away from a
    ball above the wrist."""
    with _ball_above_left_wrist() as (scene, world):
        links = world.arm_moving_links(Arm.LEFT)[-4:]
        body = scene.robot_ids[scene.robot.arms[Arm.LEFT].body]
        read = pb.getLinkStates(body, list(links), physicsClientId=scene.client)
        frame_p = np.array([s[0] for s in read])
        frame_r = quat.to_matrix(np.array([s[1] for s in read]))
        start_gap = float(world.link_distances(Arm.LEFT).distances[-5:-1].min())
        verdicts = []
        for shift in ([0.0, 0.0, -0.05], [0.0, 0.0, 0.05], [0.0, 0.04, 0.04]):
            p, q = _left_palm_path(scene, np.array(shift))
            turn = quat.to_matrix(q[:, 0]) @ quat.to_matrix(q[0, 0]).T  # (N, 3, 3)
            positions = np.einsum("nij,lj->nli", turn, frame_p - p[0, 0]) + p[:, 0, None]
            rotations = np.einsum("nij,ljk->nlik", turn, frame_r)
            quaternions = quat.from_matrix(rotations)
            for margin in (start_gap - 0.01, start_gap + 0.03):
                rigid = world.check_attached_links(p, q, 4, margin)
                posed = world.check_link_frames(Arm.LEFT, links, positions, quaternions, margin)
                np.testing.assert_array_equal(posed, rigid)
                verdicts.append(bool(rigid.any()))
        assert any(verdicts) and not all(verdicts)  # both answers were asked for


def test_elements_are_posed_as_their_frames_composed_with_their_shapes() -> None:
    """The compiled pose pass is the rigid composition ``frame * shape`` (and the sphere centre
    carried along), element by element, to rounding."""
    from worlds.collision_geometry import _moving_poses

    rng = np.random.default_rng(7)
    k = 9
    frame_p = rng.normal(size=(k, 3))
    frame_q = quat.canonical(rng.normal(size=(k, 4)))
    frame_q /= np.linalg.norm(frame_q, axis=1, keepdims=True)
    shape_p = rng.normal(size=(k, 3))
    shape_q = rng.normal(size=(k, 4))
    shape_r = quat.to_matrix(shape_q / np.linalg.norm(shape_q, axis=1, keepdims=True))
    centre = rng.normal(size=(k, 3))
    positions, rotations, centres = _moving_poses(frame_p, frame_q, shape_p, shape_r, centre)
    frame_r = quat.to_matrix(frame_q)
    np.testing.assert_allclose(
        positions, np.einsum("nij,nj->ni", frame_r, shape_p) + frame_p, atol=1e-14
    )
    np.testing.assert_allclose(rotations, frame_r @ shape_r, atol=1e-14)
    np.testing.assert_allclose(
        centres, np.einsum("nij,nj->ni", frame_r @ shape_r, centre) + positions, atol=1e-14
    )


def test_a_sync_poses_each_link_element_on_its_link(world: CollisionWorld) -> None:
    """After a sync, every link element's position is its PyBullet link frame composed with
    the collision shape's offset in it: whatever the joints, base included."""
    scene = world.scene
    _set_random_configuration(scene, np.random.default_rng(3))
    world.sync()
    world._place()
    for body, links, _, rows, local_p, _ in world._link_tracks:
        for link, row, offset in zip(links, rows, local_p, strict=True):
            if link < 0:
                p, q = pb.getBasePositionAndOrientation(body, physicsClientId=scene.client)
            else:
                state = pb.getLinkState(
                    body, link, computeForwardKinematics=1, physicsClientId=scene.client
                )
                p, q = state[0], state[1]
            expected = np.asarray(p) + quat.to_matrix(np.asarray(q)) @ offset
            np.testing.assert_allclose(world._positions[row], expected, atol=1e-12)
