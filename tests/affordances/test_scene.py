"""Scene rules through the collision-query port and its pure-numpy fake."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pytest
from numpy.testing import assert_allclose

from affordances import GeometricSceneQuery, Obstacle, ReasonerConfig, reason
from affordances.scene import FloatArray, sample_polyline, segment_distances
from skills.vocabulary import Action, Arm, GraspType, Space
from tests.affordances.cases import ROBOT, parcel, small_box

START, GOAL = (0.4, -0.2, 0.1), (0.4, 0.2, 0.1)


def _carry(*obstacles: dict[str, Any]) -> tuple[Action, ...]:
    context = parcel(position=START, goals=[GOAL], obstacles=list(obstacles))
    top = reason(context, ROBOT)[0]
    assert top.grasp == GraspType.TWO_PALM_LATERAL
    return top.actions


def test_segment_distances() -> None:
    points = np.array([[0.5, 0.3, 0.0], [-0.3, 0.4, 0.0], [2.0, 0.0, 0.0]])
    starts, ends = np.zeros((2, 3)), np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    assert_allclose(
        segment_distances(points, starts, ends),
        [[0.3, np.hypot(0.5, 0.3)], [0.5, 0.5], [1.0, 2.0]],
    )


def test_sample_polyline_keeps_both_ends() -> None:
    samples = sample_polyline(np.array([[0.0, 0, 0], [1.0, 0, 0], [1.0, 1.0, 0]]), 4)
    assert samples.shape == (9, 3)
    assert_allclose(samples[[0, 4, 8]], [[0, 0, 0], [1, 0, 0], [1, 1, 0]])


def test_fake_path_clearance_is_swept_sphere_to_sphere() -> None:
    scene = GeometricSceneQuery()
    obstacles = [Obstacle("a", (0.5, 0.3, 0.0), 0.1), Obstacle("b", (1.3, 0.4, 0.0), 0.1)]
    gaps = scene.path_clearance(np.array([[0.0, 0, 0], [1.0, 0, 0]]), 0.05, obstacles)
    assert_allclose(gaps, [0.3 - 0.15, 0.5 - 0.15])
    # a path of one point is the object standing still
    still = scene.path_clearance(np.zeros((1, 3)), 0.05, obstacles[:1])
    assert_allclose(still, [np.sqrt(0.5**2 + 0.3**2) - 0.15])


def test_fake_link_clearance_uses_shoulder_to_palm_segments() -> None:
    scene = GeometricSceneQuery(shoulders={Arm.LEFT: (0.0, 0.2, 0.4), Arm.RIGHT: (0.0, -0.2, 0.4)})
    palm = np.array([[0.4, 0.2, 0.4]])
    gaps = scene.link_clearance({Arm.LEFT: palm}, [Obstacle("o", (0.2, 0.3, 0.4), 0.02)])
    assert list(gaps) == [Arm.LEFT]
    assert_allclose(gaps[Arm.LEFT], [0.1 - 0.02 - 0.04])


def test_obstacle_on_the_straight_path_adds_obstacle_steering() -> None:
    actions = _carry({"name": "ball", "position": (0.4, 0.0, 0.1), "radius": 0.05})
    assert Action.AVOID_OBSTACLE in actions
    context = parcel(
        position=START,
        goals=[GOAL],
        obstacles=[{"name": "ball", "position": (0.4, 0.0, 0.1), "radius": 0.05}],
    )
    avoid = reason(context, ROBOT)[0].skill(Action.AVOID_OBSTACLE)
    assert avoid is not None and avoid.space == Space.ABSOLUTE
    assert avoid.params["obstacles"] == ("ball",)
    assert avoid.params["obstacle_gain"] == 1.0


def test_obstacle_near_the_arm_but_off_the_path_adds_link_avoidance() -> None:
    # near the left arm's segment from its shoulder (0, 0.2, 0.4) to the palm at the goal
    # (0.4, 0.35, 0.1), 0.39 m from the object's path
    lamp = {"name": "lamp", "position": (0.1, 0.25, 0.35), "radius": 0.03}
    context = parcel(position=START, goals=[GOAL], obstacles=[lamp])
    top = reason(context, ROBOT)[0]
    assert Action.AVOID_OBSTACLE not in top.actions
    avoid = top.skill(Action.AVOID_LINKS)
    assert avoid is not None and avoid.space == Space.ABSOLUTE
    assert avoid.params["arms"] == ("left",)
    assert avoid.params["obstacles"] == ("lamp",)
    assert any(line.startswith("scene: lamp") and "left arm" in line for line in top.because)


def test_an_obstacle_above_the_path_within_the_carry_lift_adds_obstacle_steering() -> None:
    # 0.33 m over the path: 0.105 m clear of the parcel's sphere at rest height, touching it
    # once the carry has lifted it 0.12 m.
    lamp = {"name": "lamp", "position": (0.4, 0.0, 0.1 + 0.33), "radius": 0.03}
    context = parcel(position=START, goals=[GOAL], obstacles=[lamp])
    assert Action.AVOID_OBSTACLE in reason(context, ROBOT)[0].actions
    flat = ReasonerConfig(carry_lift_m=1e-3)
    assert Action.AVOID_OBSTACLE not in reason(context, ROBOT, config=flat)[0].actions


def test_a_hand_welded_above_the_palm_rides_along_its_path() -> None:
    shoulders = {Arm.LEFT: (0.0, 0.2, 0.4), Arm.RIGHT: (0.0, -0.2, 0.4)}
    palms = {Arm.LEFT: np.array([[0.4, 0.1, 0.1]]), Arm.RIGHT: np.array([[0.4, -0.1, 0.1]])}
    # Palm frame: x down, z into the object (towards the other palm): a hand 0.1 m above the
    # left palm is at (0.4, 0.1, 0.2); the ball 0.2 m above the palm is 0.1 m from its centre.
    hand = (np.array([[-0.1, 0.0, 0.0]]), np.array([0.03]))
    ball = [Obstacle("ball", (0.4, 0.1, 0.3), 0.02)]
    bare = GeometricSceneQuery(shoulders=shoulders).link_clearance(palms, ball)
    handed = GeometricSceneQuery(shoulders=shoulders, hands={Arm.LEFT: hand})
    gaps = handed.link_clearance(palms, ball)
    assert_allclose(gaps[Arm.LEFT], [0.1 - 0.03 - 0.02])
    assert bare[Arm.LEFT][0] > gaps[Arm.LEFT][0]
    assert_allclose(gaps[Arm.RIGHT], bare[Arm.RIGHT])  # no hand on the right
    # Behind the face (-z): the left palm pushes towards -y, so behind it is +y.
    behind = GeometricSceneQuery(
        shoulders=shoulders, hands={Arm.LEFT: (np.array([[0.0, 0.0, -0.1]]), np.array([0.03]))}
    )
    side = [Obstacle("ball", (0.4, 0.3, 0.1), 0.02)]
    assert_allclose(behind.link_clearance(palms, side)[Arm.LEFT], [0.1 - 0.03 - 0.02])


def test_far_obstacle_adds_neither() -> None:
    actions = _carry({"name": "shelf", "position": (1.5, 1.5, 1.0), "radius": 0.05})
    assert Action.AVOID_OBSTACLE not in actions and Action.AVOID_LINKS not in actions


def test_one_arm_grasp_checks_only_its_arm() -> None:
    # the box is on the right: an obstacle by the left shoulder does not matter
    context = small_box(obstacles=[{"name": "cup", "position": (0.05, 0.25, 0.35), "radius": 0.04}])
    assert Action.AVOID_LINKS not in reason(context, ROBOT)[0].actions


class _RecordingScene:
    """A port that reports fixed clearances and records what it was asked."""

    def __init__(self, path_gap: float, link_gap: float) -> None:
        self.path_gap, self.link_gap = path_gap, link_gap
        self.paths: list[FloatArray] = []
        self.arms: list[tuple[Arm, ...]] = []

    def path_clearance(
        self, waypoints: FloatArray, object_radius: float, obstacles: Sequence[Obstacle]
    ) -> FloatArray:
        self.paths.append(waypoints)
        return np.full(len(obstacles), self.path_gap)

    def link_clearance(
        self, palm_paths: Mapping[Arm, FloatArray], obstacles: Sequence[Obstacle]
    ) -> dict[Arm, FloatArray]:
        self.arms.append(tuple(palm_paths))
        return {arm: np.full(len(obstacles), self.link_gap) for arm in palm_paths}


@pytest.mark.parametrize(
    ("path_gap", "link_gap", "expected"),
    [
        # Near the path, the object's own surface joins link-level avoidance (default rule).
        (0.01, 1.0, {Action.AVOID_OBSTACLE, Action.AVOID_LINKS}),
        (1.0, 0.01, {Action.AVOID_LINKS}),
        (1.0, 1.0, set()),
        (-0.1, -0.1, {Action.AVOID_OBSTACLE, Action.AVOID_LINKS}),
    ],
)
def test_any_port_implementation_drives_the_scene_rules(
    path_gap: float, link_gap: float, expected: set[Action]
) -> None:
    scene = _RecordingScene(path_gap, link_gap)
    context = parcel(obstacles=[{"name": "box", "position": (1.0, 1.0, 1.0), "radius": 0.1}])
    top = reason(context, ROBOT, scene=scene)[0]
    avoid = {Action.AVOID_OBSTACLE, Action.AVOID_LINKS}
    assert set(top.actions) & avoid == expected
    assert_allclose(scene.paths[0], [context.position, *context.goals])
    assert scene.arms[0] == (Arm.LEFT, Arm.RIGHT)
