"""FakeWorld's trajectory check judges the held object as the box it is, turned as it is."""

from __future__ import annotations

import numpy as np
import pytest

from planner.port import ObstacleInfo, Pose
from planner.testing import FakeWorld
from planner.testing.fake_world import FakeObject
from skills import quaternion as quat
from skills.vocabulary import ARMS

BOX = np.array([0.20, 0.30, 0.15])  # half extents 0.10, 0.15, 0.075
CENTRE = np.array([0.55, 0.0, 0.675])
FAR_PALMS = np.array([[0.35, 0.45, 0.85], [0.35, -0.45, 0.85]])


def yaw(angle: float) -> np.ndarray:
    return quat.from_axis_angle([0.0, 0.0, 1.0], angle)


def world_with(sphere_at: np.ndarray, radius: float = 0.05) -> FakeWorld:
    world = FakeWorld(
        objects=[FakeObject("parcel", BOX)],
        obstacles=[ObstacleInfo("ball", np.asarray(sphere_at, dtype=float), radius)],
    )
    world.set_active_obstacles(["ball"])
    return world


def check(world: FakeWorld, q: np.ndarray, margin: float) -> tuple[bool, float]:
    result = world.check_trajectory(
        "parcel",
        CENTRE[None],
        q[None],
        FAR_PALMS[None],
        np.repeat(world.rest_palm_pose(ARMS[0]).orientation[None, None], 2, axis=1),
        margin,
    )
    return result.clear, result.min_distance_m


def test_a_sphere_over_the_top_face_is_its_gap_from_the_face() -> None:
    # 1 cm above the top face: its bounding sphere (radius 0.195 m) would have refused it.
    world = world_with(CENTRE + [0.0, 0.0, 0.075 + 0.05 + 0.01])
    assert check(world, yaw(0.0), 0.005)[0]
    assert not check(world, yaw(0.0), 0.02)[0]


@pytest.mark.parametrize("angle, clear", [(0.0, False), (np.pi / 2.0, True)])
def test_the_box_is_turned_as_its_orientation_says(angle: float, clear: bool) -> None:
    # The sphere's surface 0.11 m along y from the centre: the long side (half 0.15) overlaps
    # it when square and, turned a quarter, the short side (half 0.10) leaves 1 cm.
    world = world_with(CENTRE + [0.0, 0.10 + 0.01 + 0.05, 0.0])
    assert check(world, yaw(angle), 0.005)[0] is clear


def test_a_sphere_whose_centre_is_inside_is_a_negative_gap() -> None:
    world = world_with(CENTRE + [0.0, 0.0, 0.05])
    clear, _ = check(world, yaw(0.0), 0.0)
    assert not clear


@pytest.mark.parametrize("angle", [0.0, 0.4, 1.2, -2.5])
def test_the_gap_agrees_with_the_worlds_own_obstacle_gap(angle: float) -> None:
    world = FakeWorld(
        objects=[FakeObject("parcel", BOX, pose=Pose.of(CENTRE, yaw(angle)))],
        obstacles=[ObstacleInfo("ball", CENTRE + [0.12, 0.2, 0.09], 0.03)],
    )
    world.set_active_obstacles(["ball"])
    gap = world.obstacle_gap("parcel", 1.0)
    assert gap is not None
    assert check(world, yaw(angle), 0.0)[1] == pytest.approx(gap.distance_m, abs=1e-9)
