"""A table found off its stated height: measured from the object resting on it
(set_down.table_found_dz), and the goals that rest the object on it raised with it
(composition.on_found_table)."""

from __future__ import annotations

import numpy as np
import pytest

from planner.composition import on_found_table
from planner.leaves.set_down import TABLE_FOUND_FROM_M, TABLE_FOUND_WITHIN_M, table_found_dz
from planner.port import Move, Pose
from planner.testing import FakeWorld, grasp_object
from planner.testing.fake_world import FakeObject
from skills import quaternion as quat
from skills.library import SkillLibrary

BOX = np.array([0.20, 0.30, 0.15])
TABLE = 0.6  # the fake's stated (and only) table top, m
ON_ITS_SIDE = quat.from_axis_angle(np.array([1.0, 0.0, 0.0]), np.pi / 2.0)


def _resting(dz: float, orientation: np.ndarray | None = None) -> FakeWorld:
    """A parcel resting as on a table ``dz`` m above the stated one (nothing holds it)."""
    q = np.array([0.0, 0.0, 0.0, 1.0]) if orientation is None else orientation
    half = 0.5 * float(np.abs(quat.to_matrix(q)[2]) @ BOX)
    return FakeWorld(
        objects=[FakeObject("parcel", BOX, pose=Pose(np.array([0.55, 0.0, TABLE + half + dz]), q))],
        table_height=TABLE,
    )


@pytest.mark.parametrize(
    "dz", [0.02, -0.03, TABLE_FOUND_FROM_M + 1e-4, 1e-4 - TABLE_FOUND_WITHIN_M]
)
def test_the_table_is_found_where_the_resting_object_says(dz: float) -> None:
    assert table_found_dz(_resting(dz), "parcel") == pytest.approx(dz)
    # Turned onto its side, its lowest point is half its y extent below its centre.
    assert table_found_dz(_resting(dz, ON_ITS_SIDE), "parcel") == pytest.approx(dz)


@pytest.mark.parametrize("dz", [0.0, 0.004, -0.004, 0.051, -0.08])
def test_settling_noise_and_other_supports_leave_the_stated_table(dz: float) -> None:
    # Within TABLE_FOUND_FROM_M: the stated height stands. Beyond TABLE_FOUND_WITHIN_M: it
    # rests on something else (another object), not on the table.
    assert table_found_dz(_resting(dz), "parcel") == 0.0


@pytest.mark.usefixtures("clean_blackboard")
def test_an_object_the_palms_carry_finds_no_table(library: SkillLibrary) -> None:
    world = _resting(0.0)
    grasp_object(world, library)
    obj = world._objects["parcel"]
    obj.pose = Pose(obj.pose.position + [0.0, 0.0, 0.02], obj.pose.orientation)
    assert table_found_dz(world, "parcel") == 0.0


def test_a_goal_on_the_stated_table_goes_down_with_a_table_found_lower() -> None:
    world = _resting(0.0)
    on_table = Move(Pose.of([0.6, 0.1, TABLE + BOX[2] / 2.0]), ("ball",))
    lowered = on_found_table(world, "parcel", on_table, -0.025)
    assert lowered.goal.position == pytest.approx(on_table.goal.position - [0.0, 0.0, 0.025])
    assert lowered.goal.orientation == pytest.approx(on_table.goal.orientation)
    assert lowered.obstacles == on_table.obstacles
    # On its side: on the table when its centre is half its y extent over the top.
    side = Move(Pose(np.array([0.6, 0.1, TABLE + BOX[1] / 2.0]), ON_ITS_SIDE))
    assert on_found_table(world, "parcel", side, -0.02).goal.position[2] == pytest.approx(
        TABLE + BOX[1] / 2.0 - 0.02
    )


def test_a_table_found_higher_is_left_to_the_set_down_by_feel() -> None:
    world = _resting(0.0)
    on_table = Move(Pose.of([0.6, 0.1, TABLE + BOX[2] / 2.0]))
    assert on_found_table(world, "parcel", on_table, 0.02) is on_table
    assert on_found_table(world, "parcel", on_table, 0.0) is on_table


def test_goals_off_the_stated_table_and_fixture_moves_stay_as_stated() -> None:
    world = _resting(0.0)
    held_up = Move(Pose.of([0.6, 0.1, TABLE + BOX[2] / 2.0 + 0.05]))
    assert on_found_table(world, "parcel", held_up, -0.02) is held_up
    slot = Move(Pose.of([0.6, 0.1, TABLE + BOX[2] / 2.0]), fixture="slot")
    assert on_found_table(world, "parcel", slot, -0.02) is slot
