"""Grasp closes from where the palms were sent (PalmControl.palm_target), not from where a
biased actuator holds them: the palms' references, hence their force, do not jump by the bias
when closing starts."""

from __future__ import annotations

import numpy as np
import py_trees
import pytest
from numpy.testing import assert_allclose
from py_trees.common import Status

from planner.leaves import Approach, Grasp
from planner.port import Pose
from planner.testing import FakeWorld
from planner.testing.harness import tick_until
from skills.library import SkillLibrary
from skills.vocabulary import ARMS, Arm
from tests.planner.test_leaves_fake import DT, ready, select

#: Where the biased left palm settles from its target: 2 cm towards the parcel's face (-y)
#: and 1 cm up, as Hard mode's torque bias holds a palm.
BIAS = np.array([0.0, -0.02, 0.01])


def _first_closing_commands(library: SkillLibrary, bias: np.ndarray | None) -> dict[Arm, Pose]:
    py_trees.blackboard.Blackboard.clear()
    world = FakeWorld()
    select(world, library)
    approach = ready(Approach("approach"), world, library, object="parcel")
    assert tick_until(approach, world, DT).final == Status.SUCCESS
    if bias is not None:
        world.bias_palm(Arm.LEFT, bias)
        world.advance(DT)
        measured = world.palm_pose(Arm.LEFT).position
        assert_allclose(measured, world.palm_target(Arm.LEFT).position + bias)
    world.commands.clear()
    grasp = ready(Grasp("grasp"), world, library, object="parcel", plan="{plan}", state="{state}")
    log = tick_until(grasp, world, DT)
    assert log.final == Status.SUCCESS, log.feedback
    return {c.arm: c.pose for c in reversed(world.commands)}  # each arm's first command


@pytest.mark.usefixtures("clean_blackboard")
def test_grasp_starts_from_the_palms_targets_not_where_a_bias_holds_them(
    library: SkillLibrary,
) -> None:
    unbiased = _first_closing_commands(library, None)
    biased = _first_closing_commands(library, BIAS)
    for arm in ARMS:
        assert_allclose(biased[arm].position, unbiased[arm].position, atol=1e-9)
        assert_allclose(biased[arm].orientation, unbiased[arm].orientation, atol=1e-9)
