"""Fixtures to tick one leaf against the in-memory world (and, marked sim, against PyBullet)."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import py_trees
import pytest

from planner.port import Move, ObstacleInfo, Pose
from planner.testing import FakeObject, FakeWorld
from skills import quaternion as quat
from skills.default_library import build_default_library
from skills.library import SkillLibrary

DT = 1.0 / 60.0


@pytest.fixture(autouse=True)
def clean_blackboard() -> Iterator[None]:
    """py_trees' blackboard is global: every test starts and ends with it empty."""
    py_trees.blackboard.Blackboard.clear()
    yield
    py_trees.blackboard.Blackboard.clear()


@pytest.fixture(scope="session")
def library() -> SkillLibrary:
    """The default library, learnt once per test session."""
    return build_default_library()


def three_moves() -> dict[str, tuple[Move, ...]]:
    """Centre, right, left: the paper's three consecutive moves, the last two with obstacles."""
    return {
        "parcel": (
            Move(Pose.of([0.65, 0.0, 0.675])),
            Move(Pose.of([0.60, -0.15, 0.675]), ("ball_right",)),
            Move(
                Pose.of([0.60, 0.15, 0.675], quat.from_axis_angle([0, 0, 1], 0.3)), ("ball_left",)
            ),
        )
    }


@pytest.fixture
def fake_world() -> FakeWorld:
    """A parcel on the table, two obstacles, the three-move task."""
    return FakeWorld(
        objects=[FakeObject("parcel", np.array([0.20, 0.30, 0.15]))],
        obstacles=[
            ObstacleInfo("ball_right", np.array([0.625, -0.075, 0.80]), 0.04),
            ObstacleInfo("ball_left", np.array([0.72, 0.0, 0.76]), 0.04),
        ],
        moves=three_moves(),
    )
