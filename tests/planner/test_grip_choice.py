"""A re-grasp beside an obstacle takes the other faces that make the move's turn.

A box set down turned near half way between two face pairs (a 45 degree goal) can be held on
either pair for a small turn. When every way in to the usual pair ends with a palm in an
obstacle, ``Approach`` comes in to the other pair, and ``Grasp`` closes on the faces the palms
came to.
"""

from __future__ import annotations

import numpy as np
import pytest
from py_trees.common import Status

from planner.grips import facing_quarter_turns, grasp_options, lateral_geometry
from planner.leaves import Approach
from planner.port import ObstacleInfo, Pose
from planner.testing import CONTROL_DT, FakeWorld, grasp_object, tick_until
from planner.testing.harness import set_up
from skills import quaternion as quat
from skills.library import SkillLibrary
from skills.vocabulary import ARMS, Arm

STANDOFF_M = 0.04
CENTRE = np.array([0.55, 0.0, 0.675])


def turned_parcel_world(yaw_deg: float, obstacle_at: np.ndarray | None) -> FakeWorld:
    from planner.testing.fake_world import FakeObject

    pose = Pose.of(CENTRE, quat.from_axis_angle(np.array([0.0, 0.0, 1.0]), np.radians(yaw_deg)))
    obstacles = [] if obstacle_at is None else [ObstacleInfo("ball", obstacle_at, 0.03)]
    world = FakeWorld(
        objects=[FakeObject("parcel", np.array([0.20, 0.30, 0.15]), pose=pose)],
        obstacles=obstacles,
    )
    world.set_active_obstacles([o.name for o in obstacles])
    return world


def pregrasp_position(world: FakeWorld, quarter_turns: int, arm: Arm) -> np.ndarray:
    g = lateral_geometry(world, "parcel", quarter_turns)
    obj = world.object_pose("parcel")
    relative = g.position(arm) - STANDOFF_M * g.normal(arm)
    return np.asarray(obj.position + quat.rotate(obj.orientation, relative))


def approach(world: FakeWorld, library: SkillLibrary) -> tuple[Status, str]:
    leaf = set_up(Approach("approach"), world, library, object="parcel", standoff_m=STANDOFF_M)
    log = tick_until(leaf, world, CONTROL_DT)
    return log.final, log.feedback


@pytest.mark.usefixtures("clean_blackboard")
def test_two_pairs_make_no_turn_of_a_box_turned_44_degrees() -> None:
    world = turned_parcel_world(44.0, None)
    usual, other = grasp_options(world, "parcel")
    assert usual != other and (usual - other) % 2 == 1


@pytest.mark.usefixtures("clean_blackboard")
def test_the_usual_faces_where_their_way_in_is_clear(library: SkillLibrary) -> None:
    world = turned_parcel_world(44.0, None)
    usual = grasp_options(world, "parcel")[0]
    status, _ = approach(world, library)
    assert status == Status.SUCCESS
    assert facing_quarter_turns(world, "parcel") == usual


@pytest.mark.usefixtures("clean_blackboard")
def test_an_obstacle_at_the_usual_faces_sends_the_palms_to_the_other_pair(
    library: SkillLibrary,
) -> None:
    free = turned_parcel_world(44.0, None)
    usual, other = grasp_options(free, "parcel")
    # The sphere stands where the usual pair's left palm would wait, 3 cm further out.
    g = lateral_geometry(free, "parcel", usual)
    obj = free.object_pose("parcel")
    out = quat.rotate(obj.orientation, -g.normal(Arm.LEFT))
    ball = pregrasp_position(free, usual, Arm.LEFT) + 0.03 * out
    world = turned_parcel_world(44.0, ball)
    status, feedback = approach(world, library)
    assert status == Status.SUCCESS, feedback
    assert "on the other faces that make the turn" in feedback
    assert facing_quarter_turns(world, "parcel") == other
    for arm in ARMS:
        assert (
            np.linalg.norm(world.palm_pose(arm).position - pregrasp_position(world, other, arm))
            < 3e-3
        )


@pytest.mark.usefixtures("clean_blackboard")
def test_the_grasp_closes_on_the_faces_the_palms_came_to(library: SkillLibrary) -> None:
    free = turned_parcel_world(44.0, None)
    usual, other = grasp_options(free, "parcel")
    g = lateral_geometry(free, "parcel", usual)
    obj = free.object_pose("parcel")
    out = quat.rotate(obj.orientation, -g.normal(Arm.LEFT))
    world = turned_parcel_world(44.0, pregrasp_position(free, usual, Arm.LEFT) + 0.03 * out)
    grasp_object(world, library)
    assert facing_quarter_turns(world, "parcel") == other
    obj = world.object_pose("parcel")
    for arm in ARMS:
        # Pressed into the face by the squeeze (the fake's contact is a 1 kN/m spring).
        gap = {
            k: np.linalg.norm(
                world.palm_pose(arm).position
                - obj.position
                - quat.rotate(obj.orientation, lateral_geometry(world, "parcel", k).position(arm))
            )
            for k in (usual, other)
        }
        assert gap[other] < 0.03 < gap[usual]
        assert world.contact_force(arm, "parcel") > 0.0


@pytest.mark.usefixtures("clean_blackboard")
def test_palms_at_rest_face_no_pair() -> None:
    assert facing_quarter_turns(turned_parcel_world(0.0, None), "parcel") is None
