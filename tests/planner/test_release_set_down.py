"""Release sets down an object the palms still carry before it opens them: a re-grasp after a
slip in the air must not drop the object onto what stands below (default world, trial 352)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import py_trees
import pytest
from py_trees.common import Status

from planner.leaves import Release, Transport
from planner.leaves.set_down import lowered, palm_load_n, supported_below_n
from planner.leaves.transport import SET_DOWN_DEPTH_M
from planner.testing import CONTROL_DT, grasp_object
from planner.testing.harness import TickLog
from skills import quaternion as quat
from skills.composer import grasped_state
from skills.library import SkillLibrary
from skills.vocabulary import ARMS
from worlds.sim_world import SimWorld

Tick = Callable[..., TickLog]


def test_lowered_moves_the_object_and_both_palms_down_keeping_the_grip() -> None:
    state = grasped_state(
        [0.5, 0.1, 0.8],
        quat.from_axis_angle([0, 0, 1], 0.4),
        ([0.0, 0.15, 0.0], quat.IDENTITY),
        ([0.0, -0.15, 0.0], quat.IDENTITY),
    )
    down = lowered(state, 0.03, 0.05)
    np.testing.assert_allclose(down.object.position, [0.5, 0.1, 0.77])
    np.testing.assert_allclose(down.object.velocity, [0.0, 0.0, -0.05])
    assert down.left is state.left and down.right is state.right
    up = lowered(state, -0.02)
    assert up.object.position[2] == pytest.approx(0.82)


def held_in_the_air(tick_leaf: Tick, below_m: float) -> tuple[object, float]:
    """A FakeWorld whose table stands ``below_m`` below where Transport gave up searching for
    it: the parcel is left held :data:`SET_DOWN_DEPTH_M` below the goal. Returns the world and
    the parcel's rest height on that table."""
    from tests.planner.test_set_down import carry_first_move, lowered_table_world

    world = lowered_table_world(SET_DOWN_DEPTH_M + below_m)
    log, _ = carry_first_move(world, tick_leaf)
    assert log.final == Status.FAILURE and "no surface took the object" in log.feedback
    assert palm_load_n(world, "parcel") > supported_below_n(world, "parcel")
    return world, world.table_height + 0.075


def release(world: Any, tick_leaf: Tick, **ports: Any) -> TickLog:
    """Tick a Release of the parcel from the blackboard's state to its end."""
    leaf = Release("release")
    return tick_leaf(
        leaf, world, object="parcel", from_state="{state}", to_state="{state}", **ports
    )


def test_a_carried_object_is_set_down_on_the_surface_below_then_let_go(tick_leaf: Tick) -> None:
    world, resting = held_in_the_air(tick_leaf, 0.04)
    t0 = world.time()
    log = release(world, tick_leaf)
    assert log.final == Status.SUCCESS, log.feedback
    assert world.object_pose("parcel").position[2] == pytest.approx(resting, abs=1.5e-3)
    assert max(world.contact_force(arm, "parcel") for arm in ARMS) < 0.5
    # It took the time of lowering 4 cm at the default 5 cm/s, and the opening after it.
    assert log.sim_time - t0 > 0.04 / 0.05


def test_no_surface_within_the_search_depth_fails_and_keeps_holding(tick_leaf: Tick) -> None:
    world, _ = held_in_the_air(tick_leaf, 0.04)
    z0 = world.object_pose("parcel").position[2]
    log = release(world, tick_leaf, set_down_m=0.02)
    assert log.final == Status.FAILURE
    assert "no surface took the object within 20 mm below where it was held" in log.feedback
    assert "not letting go" in log.feedback
    # Still held, no deeper than it searched.
    assert palm_load_n(world, "parcel") > supported_below_n(world, "parcel")
    assert world.object_pose("parcel").position[2] > z0 - 0.02 - 2e-3


def test_set_down_m_zero_opens_where_it_is(tick_leaf: Tick) -> None:
    world, _ = held_in_the_air(tick_leaf, 0.04)
    t0 = world.time()
    log = release(world, tick_leaf, set_down_m=0.0)
    assert log.final == Status.SUCCESS, log.feedback
    # The fake drops what nothing holds onto the table at once: the time says no lowering.
    assert log.sim_time - t0 < 0.04 / 0.05


def lift_in_physics(sim_world: SimWorld, library: SkillLibrary, tick_leaf: Tick) -> float:
    """Grasp the parcel and halt its first carry once it is 4 cm up; returns its rest z."""
    grasp_object(sim_world, library)
    rest_z = float(sim_world.object_pose("parcel").position[2])
    carry = Transport("carry")
    tick_leaf(
        carry,
        sim_world,
        max_ticks=1,
        object="parcel",
        move=0,
        plan="{plan}",
        from_state="{state}",
        to_state="{state}",
    )
    for _ in range(240):
        if sim_world.object_pose("parcel").position[2] > rest_z + 0.04:
            break
        sim_world.advance(CONTROL_DT)
        carry.tick_once()
    carry.stop(Status.INVALID)  # halted in the air: it hands over where it left the palms
    assert sim_world.object_pose("parcel").position[2] > rest_z + 0.04
    assert py_trees.blackboard.Blackboard.exists("/state")
    return rest_z


@pytest.mark.sim
def test_in_physics_a_release_in_the_air_sets_the_parcel_down_instead_of_dropping_it(
    sim_world: SimWorld, library: SkillLibrary, tick_leaf: Tick
) -> None:
    rest_z = lift_in_physics(sim_world, library, tick_leaf)
    log = release(sim_world, tick_leaf)
    assert log.final == Status.SUCCESS, log.feedback
    assert not sim_world.safety.dropped
    assert sim_world.object_pose("parcel").position[2] == pytest.approx(rest_z, abs=3e-3)
    assert max(sim_world.contact_force(arm, "parcel") for arm in ARMS) < 0.5


@pytest.mark.sim
def test_in_physics_opening_in_the_air_drops_the_parcel(
    sim_world: SimWorld, library: SkillLibrary, tick_leaf: Tick
) -> None:
    # What the set-down prevents: the same release told not to search drops the parcel.
    lift_in_physics(sim_world, library, tick_leaf)
    release(sim_world, tick_leaf, set_down_m=0.0)
    for _ in range(30):
        sim_world.advance(CONTROL_DT)
    assert sim_world.safety.dropped
