"""The leaf-testing helpers users get from ``planner.testing``: they bring a world to the state
the shipped tree would, and a step that fails says which leaf and why."""

from __future__ import annotations

import py_trees
import pytest
from numpy.testing import assert_allclose
from py_trees.common import Status

from affordances import SemanticAction
from planner.testing import FakeWorld, grasp_object, select_skills, set_up_carry, tick_until
from skills.composer import DualArmState
from skills.library import SkillLibrary
from skills.vocabulary import ARMS


def test_grasp_object_leaves_the_object_squeezed_and_the_state_on_the_blackboard(
    fake_world: FakeWorld, library: SkillLibrary
) -> None:
    plan = grasp_object(fake_world, library)
    assert isinstance(plan, SemanticAction)
    assert py_trees.blackboard.Blackboard.get("/plan") is plan
    assert isinstance(py_trees.blackboard.Blackboard.get("/state"), DualArmState)
    forces = [fake_world.contact_force(arm, "parcel") for arm in ARMS]
    assert all(f > 0.0 for f in forces), forces


def test_the_helpers_write_the_keys_they_are_given(
    fake_world: FakeWorld, library: SkillLibrary
) -> None:
    grasp_object(fake_world, library, plan_key="mine", state_key="held")
    assert isinstance(py_trees.blackboard.Blackboard.get("/mine"), SemanticAction)
    assert isinstance(py_trees.blackboard.Blackboard.get("/held"), DualArmState)


def test_a_failing_step_names_its_leaf_and_says_why(
    fake_world: FakeWorld, library: SkillLibrary
) -> None:
    with pytest.raises(AssertionError, match=r"^select: .*crate"):
        select_skills(fake_world, library, name="crate")
    with pytest.raises(AssertionError, match=r"^select: .*crate"):
        grasp_object(fake_world, library, name="crate")


def test_a_carry_set_up_as_the_tree_wires_it_places_the_object_and_hands_over(
    fake_world: FakeWorld, library: SkillLibrary
) -> None:
    grasp_object(fake_world, library)
    before = py_trees.blackboard.Blackboard.get("/state")
    log = tick_until(set_up_carry(fake_world, library, move=0), fake_world, max_ticks=3000)
    assert log.final == Status.SUCCESS, log.feedback
    goal = fake_world.task_moves("parcel")[0].goal.position
    assert_allclose(fake_world.object_pose("parcel").position, goal, atol=0.02)
    after = py_trees.blackboard.Blackboard.get("/state")
    assert isinstance(after, DualArmState) and after is not before


def test_wiring_a_leaf_by_hand_names_the_leaf_and_the_port_at_fault() -> None:
    # A test's bad constant had been py_trees' bare "Cannot convert Value 'high' to type
    # float", and an object passed as a constant its repr, a kilobyte long.
    import numpy as np

    from planner.leaves.conditions import IsHeld
    from planner.wiring import wire

    with pytest.raises(ValueError, match=r"^IsHeld 'held': port 'min_force_n': Cannot convert"):
        wire(IsHeld("held"), object="parcel", min_force_n="high")
    with pytest.raises(TypeError, match=r"^IsHeld 'held': port 'min_force_n': expected a constant"):
        wire(IsHeld("held"), object="parcel", min_force_n=np.zeros(3))
    wire(IsHeld("held"), object="parcel", min_force_n=np.float64(5.0))  # a number is a number
