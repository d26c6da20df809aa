"""Robot leaves ticked alone against PyBullet (DIRECT): contact-only grasp, hold, release."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest
from py_trees.common import Status

from planner.leaves import (
    AtGoal,
    IsHeld,
    PathClear,
    Release,
    Retreat,
    Transport,
)
from planner.testing import grasp_object
from planner.testing.harness import TickLog
from skills.library import SkillLibrary
from skills.vocabulary import ARMS
from worlds.sim_world import SimWorld

pytestmark = pytest.mark.sim
Tick = Callable[..., TickLog]


def test_grasp_squeezes_by_contact_alone(
    sim_world: SimWorld, library: SkillLibrary, tick_leaf: Tick
) -> None:
    grasp_object(sim_world, library)
    forces = [sim_world.contact_force(arm, "parcel") for arm in ARMS]
    assert all(8.0 < f < 60.0 for f in forces), forces
    held = tick_leaf(IsHeld("held"), sim_world, object="parcel")
    assert held.final == Status.SUCCESS, held.feedback


def test_transport_without_obstacles_places_the_parcel(
    sim_world: SimWorld, library: SkillLibrary, tick_leaf: Tick
) -> None:
    grasp_object(sim_world, library)
    log = tick_leaf(
        Transport("move0"),
        sim_world,
        max_ticks=1200,
        object="parcel",
        move=0,
        plan="{plan}",
        from_state="{state}",
        to_state="{state}",
    )
    assert log.final == Status.SUCCESS, log.feedback
    at_goal = tick_leaf(AtGoal("at_goal"), sim_world, object="parcel", move=0)
    assert at_goal.final == Status.SUCCESS, at_goal.feedback
    assert not sim_world.safety.dropped


def test_release_opens_the_palms(
    sim_world: SimWorld, library: SkillLibrary, tick_leaf: Tick
) -> None:
    grasp_object(sim_world, library)
    log = tick_leaf(
        Release("release"), sim_world, object="parcel", from_state="{state}", to_state="{state}"
    )
    assert log.final == Status.SUCCESS, log.feedback
    assert max(sim_world.contact_force(arm, "parcel") for arm in ARMS) < 0.5


def test_retreat_returns_the_palms_to_rest(
    sim_world: SimWorld, library: SkillLibrary, tick_leaf: Tick
) -> None:
    grasp_object(sim_world, library)
    tick_leaf(
        Release("release"), sim_world, object="parcel", from_state="{state}", to_state="{state}"
    )
    log = tick_leaf(Retreat("retreat"), sim_world)
    assert log.final == Status.SUCCESS, log.feedback
    for arm in ARMS:
        rest = sim_world.rest_palm_pose(arm).position
        assert np.linalg.norm(sim_world.palm_pose(arm).position - rest) < 0.02


def test_path_clear_checks_the_predicted_carry_with_fcl(
    sim_world: SimWorld, library: SkillLibrary, tick_leaf: Tick
) -> None:
    grasp_object(sim_world, library)
    # Move 2 of the default world has a sphere above its straight path: the learnt lift,
    # without avoidance, would hit it; the low carry passes under.
    lifted = tick_leaf(
        PathClear("as_demonstrated"),
        sim_world,
        object="parcel",
        move=1,
        plan="{plan}",
        from_state="{state}",
        avoid_gain=0.0,
        margin_m=0.01,
    )
    assert lifted.final == Status.FAILURE and "predicted collision" in lifted.feedback
    low = tick_leaf(
        PathClear("low"),
        sim_world,
        object="parcel",
        move=1,
        plan="{plan}",
        from_state="{state}",
        avoid_gain=0.0,
        transport_weight=0.25,
        margin_m=0.01,
    )
    assert low.final == Status.SUCCESS, low.feedback
